// Every parser of a file a user can hand in or edit, fed a bounded corpus of
// seeded mutations of a valid file: truncations, bit flips, inserted tokens
// (NaN, 1e999, huge integers, brackets), fields replaced by values of the
// wrong type or out of range, fields removed, arrays grown 2000-fold, huge
// counts and NaN floats in binary headers and bodies. Each input must give a
// Status naming the file or a valid result, never an exception, a crash or a
// hang. The corpus is the same on every run (fixed seeds).
//
// Parsers: journal.jsonl (ReadJournalRecords, VerifiedFrames, OpenForResume,
// OpenReplaySource), manifest.json (LoadCaptureCalibrationInput),
// capture.json, calibration.json, intrinsics files, helix models, heads, the
// three strand formats (.hair, .data, .ply binary and ascii) and COLMAP text
// models (cameras.txt, images.txt).

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>

#include "calibration/calibration_io.h"
#include "core/file_util.h"
#include "core/geometry_json.h"
#include "core/head_json.h"
#include "core/json_file.h"
#include "core/sha256.h"
#include "core/strand_io.h"
#include "reconstruction/colmap_model.h"
#include "rig/capture_calibration_input.h"
#include "rig/capture_dataset.h"
#include "rig/journal_records.h"
#include "rig/replay.h"
#include "simulation/helix_model.h"
#include "tests/support/calibration_documents.h"
#include "tests/support/image_test_util.h"
#include "tests/support/two_camera_rig.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr uint32_t kSeed = 20261124;

// ---- mutations --------------------------------------------------------------

void CollectPointers(const json& j, const json::json_pointer& here,
                     std::vector<json::json_pointer>* out) {
  out->push_back(here);
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) CollectPointers(*it, here / it.key(), out);
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i) CollectPointers(j[i], here / i, out);
  }
}

const std::vector<json>& HostileValues() {
  static const std::vector<json> values = {json(nullptr),
                                           json(true),
                                           json(0),
                                           json(-1),
                                           json(2.5),
                                           json(-2.5),
                                           json(1e308),
                                           json(-1e308),
                                           json(int64_t{4294967296}),
                                           json(INT64_MAX),
                                           json(UINT64_MAX),
                                           json(INT64_MIN),
                                           json(""),
                                           json("x"),
                                           json("NaN"),
                                           json("../../etc/passwd"),
                                           json(std::string(1000, 'a')),
                                           json::array(),
                                           json::object(),
                                           json::array({1, 2, 3}),
                                           json::object({{"a", 1}})};
  return values;
}

class Mutator {
 public:
  explicit Mutator(uint32_t seed) : rng_(seed) {}

  size_t Below(size_t n) {
    return n == 0 ? 0 : std::uniform_int_distribution<size_t>(0, n - 1)(rng_);
  }

  std::string MutateBytes(std::string t) {
    static const char* const kTokens[] = {
        "NaN",     "-1",   "1e999", "-0",          "99999999999999999999999",
        "\"\"",    "null", "[",     "{",           "]",
        "}",       ",",    "\n",    "\"\\u0000\"", "../../",
        "\xff\xfe"};
    const size_t at = Below(t.size() + 1);
    switch (Below(6)) {
      case 0:  // truncation
        t.resize(at);
        break;
      case 1:  // bit flips
        for (size_t k = 0, n = 1 + Below(8); k < n && !t.empty(); ++k)
          t[Below(t.size())] ^= static_cast<char>(1 << Below(8));
        break;
      case 2:
        t.insert(at, kTokens[Below(std::size(kTokens))]);
        break;
      case 3:
        t.erase(at, Below(16));
        break;
      case 4:  // a chunk repeated
        t.insert(at, t.substr(Below(t.size() + 1), Below(64)));
        break;
      default:  // digits grown to 9s: huge counts and values
        for (size_t i = at; i < std::min(t.size(), at + 12); ++i) {
          if (std::isdigit(static_cast<unsigned char>(t[i]))) t[i] = '9';
        }
    }
    return t;
  }

  json MutateJson(const json& seed) {
    json j = seed;
    std::vector<json::json_pointer> pointers;
    CollectPointers(j, json::json_pointer(), &pointers);
    const json::json_pointer target = pointers[Below(pointers.size())];
    switch (Below(4)) {
      case 0:
        j[target] = HostileValues()[Below(HostileValues().size())];
        break;
      case 1:
        if (!target.empty()) {
          json& parent = j[target.parent_pointer()];
          if (parent.is_object()) {
            parent.erase(target.back());
          } else {
            parent.erase(static_cast<size_t>(std::stoul(target.back())));
          }
        }
        break;
      case 2: {  // an array grown 2000-fold, or a value doubled
        json& node = j[target];
        if (node.is_array() && !node.empty()) {
          const json first = node[0];
          for (int k = 0; k < 2000; ++k) node.push_back(first);
        } else {
          node = json::array({node, node});
        }
        break;
      }
      default:  // one level deeper
        j[target] = json::array({j[target]});
    }
    return j;
  }

  // A mutated document as text: structural, byte-level, or both.
  std::string MutateJsonText(const json& seed) {
    switch (Below(3)) {
      case 0:
        return MutateBytes(seed.dump(1));
      case 1:
        return MutateJson(seed).dump(1);
      default:
        return MutateBytes(MutateJson(seed).dump(1));
    }
  }

  std::vector<uint8_t> MutateBinary(std::vector<uint8_t> b) {
    static const uint32_t kCounts[] = {0,           1,           65535,       65536,
                                       0x7fffffffu, 0x80000000u, 0xfffffffeu, 0xffffffffu};
    switch (Below(3)) {
      case 0: {
        const std::string t = MutateBytes(std::string(b.begin(), b.end()));
        return {t.begin(), t.end()};
      }
      case 1:  // a huge or empty count in one of the first eight words (the headers' counts)
        if (b.size() >= 4) {
          const uint32_t v = kCounts[Below(std::size(kCounts))];
          std::memcpy(b.data() + 4 * Below(std::min<size_t>(b.size() / 4, 8)), &v, 4);
        }
        return b;
      default:  // a NaN or infinite float anywhere
        if (b.size() >= 4) {
          const float v = Below(2) ? std::nanf("") : INFINITY;
          std::memcpy(b.data() + Below(b.size() - 3), &v, 4);
        }
        return b;
    }
  }

 private:
  std::mt19937 rng_;
};

// ---- checks -----------------------------------------------------------------

// Runs `parse`; an exception is a failure. The Status must be ok or name `name`.
void ExpectClean(const std::string& what, size_t iteration, const std::string& name,
                 const std::function<Status()>& parse) {
  try {
    const Status s = parse();
    if (!s.ok()) {
      EXPECT_NE(s.message().find(name), std::string::npos)
          << what << " input " << iteration << ": " << s.ToString();
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << " input " << iteration << " threw: " << e.what();
  } catch (...) {
    ADD_FAILURE() << what << " input " << iteration << " threw something";
  }
}

std::string TestDir(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("hairrig_fuzz_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// Fuzzes a JSON file reader: `iterations` mutations of `seed` written to one
// file, each read by `read` (given the path).
void FuzzJsonFile(const std::string& what, const json& seed, int iterations, uint32_t seed_number,
                  const std::function<Status(const std::string&)>& read) {
  const std::string path = TestDir(what) + "/" + what + ".json";
  WriteText(path, seed.dump(1));
  ASSERT_TRUE(read(path).ok()) << what
                               << ": the unmutated seed must be valid: " << read(path).ToString();
  Mutator m(seed_number);
  for (int i = 0; i < iterations; ++i) {
    WriteText(path, m.MutateJsonText(seed));
    ExpectClean(what, static_cast<size_t>(i), path, [&] { return read(path); });
  }
}

// ---- seeds ------------------------------------------------------------------

json HelixSeed() {
  const json element = {{"start_mm", {0, 0, 0}},
                        {"start_tangent", {0, 0, -1}},
                        {"darboux_per_mm", {0.1, 0, 0.02}},
                        {"length_mm", 4.5}};
  const json guide = {{"strand", 0}, {"elements", {element, element, element}}};
  return {{"format", "hairrig-helix-model"},
          {"version", 1},
          {"source", "strands.hair"},
          {"guides", {guide, guide}},
          {"cluster_of_strand", {0, 1, 1, -1}}};
}

json HeadSeed() {
  HeadSpec h;
  h.mesh_file = "/meshes/head.ply";
  h.scalp.defined = true;
  return HeadSpecToJson(h, "head_mesh.ply");
}

StrandSet StrandSeed(bool colors) {
  StrandSet set;
  std::mt19937 rng(kSeed);
  std::uniform_real_distribution<float> u(-50, 50);
  for (int s = 0; s < 5; ++s) {
    std::vector<Eigen::Vector3f> points;
    for (int k = 0; k < 3 + s; ++k) points.emplace_back(u(rng), u(rng), u(rng));
    set.AddStrand(points);
  }
  if (colors) set.colors.assign(set.num_points(), {200, 150, 100});
  return set;
}

// ---- the JSON documents -----------------------------------------------------

TEST(ParserFuzz, CaptureJson) {
  CaptureMetadata m;
  m.config_source = "/rigs/rig.yaml";
  m.config_dir = "/rigs";
  m.subject = "wig_03";
  m.created_utc = "2026-11-24T10:00:00.000Z";
  FuzzJsonFile("capture", m.ToJson(), 600, kSeed + 1, [](const std::string& path) {
    HR_ASSIGN_OR_RETURN(const json j, ReadJsonFile(path));
    return CaptureMetadata::FromJson(j, path).status();
  });
}

TEST(ParserFuzz, CalibrationJson) {
  FuzzJsonFile(
      "calibration", hairrig_test::CalibrationDocument(), 600, kSeed + 2,
      [](const std::string& path) {
        const auto read = ReadCalibration(path);
        if (read.ok()) {
          for (const auto& view : read->views) {
            EXPECT_TRUE(view.camera >= 0 && view.camera < static_cast<int>(read->cameras.size()));
          }
        }
        return read.status();
      });
}

TEST(ParserFuzz, IntrinsicsFiles) {
  FuzzJsonFile("intrinsics", hairrig_test::IntrinsicsDocument(), 600, kSeed + 3,
               [](const std::string& path) {
                 const auto read = ReadIntrinsicsPriors(path);
                 if (read.ok()) {
                   for (const IntrinsicsPrior& prior : *read) {
                     EXPECT_FALSE(prior.serial.empty());
                     for (double sd : prior.stddev) EXPECT_TRUE(std::isfinite(sd) && sd >= 0);
                   }
                 }
                 return read.status();
               });
}

TEST(ParserFuzz, HelixModels) {
  FuzzJsonFile("helix", HelixSeed(), 600, kSeed + 4, [](const std::string& path) {
    const auto read = ReadHelixModel(path);
    if (read.ok()) {
      for (int c : read->cluster_of_strand)
        EXPECT_TRUE(c >= -1 && c < static_cast<int>(read->guides.size()));
      for (const PiecewiseHelix& guide : read->guides) {
        for (const HelixElement& e : guide.elements)
          EXPECT_TRUE(std::isfinite(e.length_mm) && e.length_mm > 0);
      }
    }
    return read.status();
  });
}

TEST(ParserFuzz, Heads) {
  FuzzJsonFile("head", HeadSeed(), 600, kSeed + 5, [](const std::string& path) {
    HR_ASSIGN_OR_RETURN(const json j, ReadJsonFile(path));
    const auto head = HeadSpecFromJson(j, "/base", path + ": head");
    if (head.ok()) {
      EXPECT_GT(head->radii_mm.minCoeff(), 0);
    }
    return head.status();
  });
}

// ---- the strand formats -------------------------------------------------------

void FuzzStrands(StrandFormat format, const std::string& name, uint32_t seed_number) {
  const StrandSet seed =
      StrandSeed(format == StrandFormat::kPlyBinary || format == StrandFormat::kPlyAscii);
  const auto encoded = EncodeStrands(seed, format);
  ASSERT_TRUE(encoded.ok()) << encoded.status().ToString();
  ASSERT_TRUE(DecodeStrands(*encoded, format, name).ok());
  Mutator m(seed_number);
  for (size_t i = 0; i < 2500; ++i) {
    const std::vector<uint8_t> bytes = m.MutateBinary(*encoded);
    ExpectClean(name, i, name, [&] {
      const auto set = DecodeStrands(bytes, format, name);
      if (set.ok()) {
        EXPECT_TRUE(set->Check().ok()) << name << " input " << i;
      }
      return set.status();
    });
  }
}

// A COLMAP text model: each mutation hits cameras.txt, images.txt or both.
TEST(ParserFuzz, ColmapTextModels) {
  const std::string dir = TestDir("colmap");
  fs::create_directories(dir + "/images");
  // Headers the reader accepts: the images are never decoded here.
  WriteText(dir + "/images/a.jpg", PngClaiming(1200, 1600));
  WriteText(dir + "/images/b.jpg", PngClaiming(640, 480));
  const std::string cameras =
      "# Camera list\n"
      "1 OPENCV 1200 1600 1750 1751 600.5 800.5 -0.03 0.012 0.0002 -0.0001\n"
      "2 SIMPLE_RADIAL 640 480 500 320 240 0.01\n";
  const std::string images =
      "# Image list\n"
      "1 1 0 0 0 10 20 1000 1 a.jpg\n"
      "100.0 200.0 -1\n"
      "2 0.7071067811865476 0 0.7071067811865476 0 0 0 900 2 b.jpg\n"
      "\n";
  const auto read = [&] { return ReadColmapModel(dir, ColmapReadOptions{dir + "/images", ""}); };
  WriteText(dir + "/cameras.txt", cameras);
  WriteText(dir + "/images.txt", images);
  ASSERT_TRUE(read().ok()) << read().status().ToString();
  Mutator m(kSeed + 12);
  for (int i = 0; i < 600; ++i) {
    const size_t which = m.Below(3);
    WriteText(dir + "/cameras.txt", which != 1 ? m.MutateBytes(cameras) : cameras);
    WriteText(dir + "/images.txt", which != 0 ? m.MutateBytes(images) : images);
    ExpectClean("colmap", static_cast<size_t>(i), ".txt", [&] {
      const auto model = read();
      if (model.ok()) {
        for (const ReconstructionView& v : model->views) {
          EXPECT_TRUE(v.camera.width_px > 0 && v.camera.height_px > 0) << "input " << i;
          EXPECT_TRUE(std::isfinite(v.camera.fx_px) && v.camera.fx_px > 0) << "input " << i;
          EXPECT_TRUE(v.cam_from_object.translation.allFinite()) << "input " << i;
          EXPECT_TRUE(v.cam_from_object.rotation.coeffs().allFinite()) << "input " << i;
        }
      }
      return model.status();
    });
  }
}

TEST(ParserFuzz, HairFiles) { FuzzStrands(StrandFormat::kHair, "fuzz.hair", kSeed + 6); }
TEST(ParserFuzz, DataFiles) { FuzzStrands(StrandFormat::kData, "fuzz.data", kSeed + 7); }
TEST(ParserFuzz, BinaryPlyFiles) { FuzzStrands(StrandFormat::kPlyBinary, "fuzz.ply", kSeed + 8); }
TEST(ParserFuzz, AsciiPlyFiles) {
  FuzzStrands(StrandFormat::kPlyAscii, "fuzz_ascii.ply", kSeed + 9);
}

// ---- a capture folder: journal and manifest -------------------------------------

// A capture of three stored frames (views 0-2 of camera CAM-1 in a plan of 6), closed.
std::string SeedCapture() {
  const std::string dir = TestDir("capture_seed") + "/c";
  auto d = CaptureDataset::Create(dir, "name: fuzz\n", {}, {});
  EXPECT_TRUE(d.ok()) << d.status().ToString();
  std::vector<PlannedViewRecord> plan;
  for (int v = 0; v < 6; ++v)
    plan.push_back({v, v / 2, 60.0 * (v / 2), "cam", "CAM-1", {{"top", 1.0}}});
  EXPECT_TRUE((*d)->JournalPlan(plan).ok());
  (void)(*d)->Append(
      {{"event", "position_reached"}, {"stop", 0}, {"commanded_deg", 0.0}, {"measured_deg", 0.01}});
  for (int v = 0; v < 3; ++v) {
    Frame f;
    f.camera_serial = "CAM-1";
    f.width_px = 16;
    f.height_px = 8;
    f.format = PixelFormat::kMono8;
    f.data.assign(128, static_cast<uint8_t>(40 * v));
    EXPECT_TRUE((*d)->StoreFrame(f, {v, v / 2, "cam", 0, 0.01, 16, 8}).ok());
  }
  return dir;
}

std::string ReadText(const std::string& path) {
  const auto text = ReadFileText(path, kMaxFileBytes);
  return text.ok() ? *text : "";
}

// A journal line replaced by a mutation of itself, or the whole text mutated.
std::string MutateJournal(Mutator& m, const std::string& journal) {
  if (m.Below(2) == 0) return m.MutateBytes(journal);
  std::vector<std::string> lines;
  for (size_t start = 0, end; (end = journal.find('\n', start)) != std::string::npos;
       start = end + 1)
    lines.push_back(journal.substr(start, end - start));
  std::string& line = lines[m.Below(lines.size())];
  line = m.MutateJson(json::parse(line)).dump();
  if (m.Below(4) == 0) lines.push_back(line);  // a mutated copy appended as well
  std::string out;
  for (const std::string& l : lines) out += l + "\n";
  return out;
}

// Every verified frame is a planned view of the planned camera, stored under
// its one name, and its file verifies.
void ExpectOnlyGenuineFrames(const std::string& dir, const std::map<int, FrameRecord>& frames,
                             size_t i) {
  for (const auto& [view, f] : frames) {
    EXPECT_TRUE(view >= 0 && view < 6 && f.serial == "CAM-1") << "input " << i << ": view " << view;
    EXPECT_TRUE(IsFrameFileName(f.file, f.view, f.serial)) << "input " << i << ": " << f.file;
    EXPECT_TRUE(VerifyFrameFile(dir, f.file, f.bytes, f.sha256).ok())
        << "input " << i << ": " << f.file;
  }
}

TEST(ParserFuzz, JournalRecords) {
  const std::string seed_dir = SeedCapture();
  const std::string journal = ReadText(seed_dir + "/journal.jsonl");
  Mutator m(kSeed + 10);
  const std::string work = TestDir("journal");
  for (size_t i = 0; i < 400; ++i) {
    const std::string dir = work + "/c" + std::to_string(i % 2);
    fs::remove_all(dir);
    fs::copy(seed_dir, dir, fs::copy_options::recursive);
    WriteText(dir + "/journal.jsonl", MutateJournal(m, journal));
    ExpectClean("journal (read-only)", i, dir, [&] {
      HR_ASSIGN_OR_RETURN(const auto records, ReadJournalRecords(dir + "/journal.jsonl"));
      HR_ASSIGN_OR_RETURN(const auto frames, VerifiedFrames(dir, records));
      ExpectOnlyGenuineFrames(dir, frames, i);
      return OpenReplaySource(dir, {}).status();
    });
    if (i % 3 != 0) continue;
    ExpectClean("journal (resume)", i, dir, [&] {
      ResumeReport report;
      HR_ASSIGN_OR_RETURN(const auto dataset, CaptureDataset::OpenForResume(dir, {}, &report));
      std::map<int, FrameRecord> frames;
      for (const FrameRecord& f : dataset->VerifiedFrames()) frames[f.view] = f;
      ExpectOnlyGenuineFrames(dir, frames, i);
      return Status::Ok();
    });
  }
}

// A capture folder calibration can load: a rig.yaml snapshot with two cameras
// and etc/calib-box.yaml as its box, two frames, and the manifest `seed`.
std::string CalibrationCapture(json* seed) {
  const std::string dir = TestDir("manifest_capture");
  fs::create_directories(dir + "/frames");
  WriteText(dir + "/rig.yaml", hairrig_test::kTwoCameraRigYaml);
  CaptureMetadata metadata;
  metadata.config_dir = fs::absolute("etc").string();
  WriteText(dir + "/capture.json", metadata.ToJson().dump());
  json frames = json::array();
  for (int v = 0; v < 2; ++v) {
    const std::string serial = v == 0 ? "SIM-CAM-UPPER" : "SIM-CAM-LOWER";
    const std::string file = FrameFileName(v, serial, "png");
    const std::string content = "not an image, frame " + std::to_string(v);
    WriteText(dir + "/" + file, content);
    frames.push_back({{"view", v},
                      {"stop", 0},
                      {"serial", serial},
                      {"camera", v == 0 ? "upper" : "lower"},
                      {"file", file},
                      {"bytes", content.size()},
                      {"sha256", Sha256Hex(content.data(), content.size())},
                      {"angle_measured_deg", 0.01}});
  }
  *seed = {
      {"format", "hairrig-capture"}, {"version", 1}, {"status", "complete"}, {"frames", frames}};
  return dir;
}

TEST(ParserFuzz, Manifests) {
  json seed;
  const std::string dir = CalibrationCapture(&seed);
  const std::string path = dir + "/manifest.json";
  WriteText(path, seed.dump(1));
  const auto unmutated = LoadCaptureCalibrationInput(dir);
  ASSERT_TRUE(unmutated.ok()) << unmutated.status().ToString();
  for (const CalibrationFrame& frame : unmutated->frames)
    EXPECT_EQ(frame.unusable, "") << frame.name;
  Mutator m(kSeed + 11);
  for (size_t i = 0; i < 300; ++i) {
    WriteText(path, m.MutateJsonText(seed));
    ExpectClean("manifest", i, path, [&] {
      const auto input = LoadCaptureCalibrationInput(dir);
      if (input.ok()) {
        for (const CalibrationFrame& frame : input->frames) {
          EXPECT_TRUE(IsFrameFileName(frame.name, frame.view,
                                      input->cameras[static_cast<size_t>(frame.camera)].serial))
              << "input " << i << ": " << frame.name;
        }
      }
      return input.status();
    });
  }
}

}  // namespace
}  // namespace hairrig
