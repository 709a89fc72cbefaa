// Seeded mutation fuzzing of the YAML config reader (core/config.h) and the
// core loaders built on it: every mutant of the shipped configs is either
// refused with a short message naming the file, or read; nothing throws,
// hangs or prints the input back whole.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

#include "core/calib_box.h"
#include "core/charuco_board.h"
#include "core/config.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;

constexpr uint32_t kSeed = 20240611;
constexpr int kMutantsPerSeed = 400;
constexpr size_t kMaxMessageBytes = 600;

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string Join(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

// Values that stand where a number, a name or a section was.
const std::vector<std::string> kHostileValues = {"1e12",
                                                 "-1e308",
                                                 "1e999",
                                                 "99999999999999999999999",
                                                 ".nan",
                                                 ".inf",
                                                 "-.inf",
                                                 "0x7fffffff",
                                                 "-0",
                                                 "[1, 2, 3]",
                                                 "[1e12, 3]",
                                                 "[-5, 1e300, .nan]",
                                                 "{a: 1}",
                                                 "~",
                                                 "''",
                                                 "\"\\x00\"",
                                                 "&a [*a]",
                                                 "*nope",
                                                 "!!binary AAAA",
                                                 "yes",
                                                 "/etc/passwd",
                                                 std::string(300, 'w')};

class Mutator {
 public:
  explicit Mutator(uint32_t seed) : rng_(seed) {}

  std::string Mutate(const std::string& text) {
    switch (Pick(7)) {
      case 0:
        return text.substr(0, Pick(text.size() + 1));  // truncation
      case 1:
        return FlipBits(text);
      case 2:
        return DuplicateLine(text);
      case 3:
        return ReplaceValue(text);
      case 4:
        return text + "---\n" + text;  // a second document
      case 5:
        return RepeatLine(text);
      default:
        return FlipBits(ReplaceValue(text));
    }
  }

 private:
  size_t Pick(size_t n) {
    return n == 0 ? 0 : std::uniform_int_distribution<size_t>(0, n - 1)(rng_);
  }

  std::string FlipBits(std::string text) {
    if (text.empty()) return text;
    for (size_t i = 0, n = 1 + Pick(4); i < n; ++i)
      text[Pick(text.size())] ^= static_cast<char>(1u << Pick(8));
    return text;
  }

  std::string DuplicateLine(const std::string& text) {
    std::vector<std::string> lines = Lines(text);
    if (lines.empty()) return text;
    const size_t i = Pick(lines.size());
    lines.insert(lines.begin() + static_cast<long>(Pick(lines.size() + 1)), lines[i]);
    return Join(lines);
  }

  std::string RepeatLine(const std::string& text) {
    std::vector<std::string> lines = Lines(text);
    if (lines.empty()) return text;
    const std::string line = lines[Pick(lines.size())];
    lines.insert(lines.end(), 200 + Pick(2000), line);
    return Join(lines);
  }

  // The text after one line's first ": " becomes a hostile value.
  std::string ReplaceValue(const std::string& text) {
    std::vector<std::string> lines = Lines(text);
    for (int attempt = 0; attempt < 8 && !lines.empty(); ++attempt) {
      std::string& line = lines[Pick(lines.size())];
      const size_t colon = line.find(": ");
      if (colon == std::string::npos) continue;
      line = line.substr(0, colon + 2) + kHostileValues[Pick(kHostileValues.size())];
      break;
    }
    return Join(lines);
  }

  std::mt19937 rng_;
};

// Reads every field of `node` as each type in turn, as loaders do with a
// field of the wrong type; nothing may throw.
void ReadEverything(const ConfigNode& node, int depth) {
  if (depth > 6) return;
  for (const std::string& key : node.Keys()) {
    node.Number(key, 0.0);
    node.Integer(key, 0);
    node.String(key, "");
    node.Bool(key, false);
    node.Numbers(key, 0, {.min = -3600, .max = 3600});
    node.Strings(key);
    for (const ConfigNode& item : node.OptionalItems(key)) ReadEverything(item, depth + 1);
    ReadEverything(node.OptionalChild(key), depth + 1);
  }
}

// A refusal is short and names the file.
void ExpectCleanMessage(const Status& status, const std::string& origin, const std::string& input) {
  const std::string& m = status.message();
  EXPECT_LE(m.size(), kMaxMessageBytes) << m;
  EXPECT_NE(m.find(origin), std::string::npos)
      << "the message names the file: " << m << "\ninput:\n"
      << input;
}

struct Seed {
  std::string path;
  // Runs a core loader on a file holding the text; empty for the reader alone.
  std::function<Status(const std::string&)> loader;
};

std::vector<Seed> Seeds() {
  return {{"etc/sim-rig.yaml", nullptr},
          {"etc/rig-example.yaml", nullptr},
          {"etc/scenes/default.yaml", nullptr},
          {"tests/data/small_rig.yaml", nullptr},
          {"etc/calib-box.yaml", [](const std::string& p) { return LoadCalibBox(p).status(); }},
          {"etc/charuco-board.yaml",
           [](const std::string& p) { return LoadChArUcoBoard(p).status(); }}};
}

TEST(ConfigFuzz, EveryMutantIsRefusedCleanlyOrRead) {
  const fs::path dir = fs::temp_directory_path() / ("config_fuzz_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  Mutator mutator(kSeed);
  int refused = 0, read = 0;
  for (const Seed& seed : Seeds()) {
    const std::string original = ReadText(seed.path);
    ASSERT_FALSE(original.empty()) << seed.path << " (run from the repository root)";
    for (int i = 0; i < kMutantsPerSeed; ++i) {
      const std::string text = mutator.Mutate(original);
      auto root = ConfigNode::LoadString(text, "mutant.yaml");
      if (!root.ok()) {
        ++refused;
        ExpectCleanMessage(root.status(), "mutant.yaml", text);
        continue;
      }
      ++read;
      ReadEverything(*root, 0);
      if (!root->ok()) ExpectCleanMessage(root->status(), "mutant.yaml", text);
      if (!seed.loader) continue;
      const std::string file = (dir / "mutant.yaml").string();
      std::ofstream(file, std::ios::binary) << text;
      const Status loaded = seed.loader(file);
      if (!loaded.ok()) ExpectCleanMessage(loaded, file, text);
    }
  }
  fs::remove_all(dir);
  // The corpus exercises both outcomes.
  EXPECT_GT(refused, kMutantsPerSeed);
  EXPECT_GT(read, kMutantsPerSeed);
}

}  // namespace
}  // namespace hairrig
