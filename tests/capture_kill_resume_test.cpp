// Kill-and-resume: a capture process is killed with SIGKILL at many different
// moments (crash points inside a frame write, between the rename and the
// journal record, inside a journal append and a manifest write, and at timed
// instants), then resumed with `hairrig capture --resume`. Each resumed capture
// must be complete, every checksum must verify (recomputed with sha256sum), and
// no frame that verified before the resume may be shot again or touched.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "tests/support/capture_test_util.h"

namespace hairrig {
namespace {

namespace fs = std::filesystem;
using namespace hairrig::testing;

struct RunResult {
  bool killed = false;  // ended by SIGKILL
  int exit_code = -1;
};

// Runs `hairrig capture` with an optional crash point; kills it after
// `kill_after` if that is positive.
RunResult RunHairrig(const std::vector<std::string>& args, const std::string& crash_at,
                     std::chrono::milliseconds kill_after) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!crash_at.empty())
      ::setenv("HAIRRIG_CRASH_AT", crash_at.c_str(), 1);
    else
      ::unsetenv("HAIRRIG_CRASH_AT");
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    std::vector<char*> argv{const_cast<char*>(HAIRRIG_BIN)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(HAIRRIG_BIN, argv.data());
    ::_exit(127);
  }
  if (kill_after.count() > 0) {
    std::this_thread::sleep_for(kill_after);
    ::kill(pid, SIGKILL);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  RunResult r;
  r.killed = WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

struct FileIdentity {
  ino_t inode = 0;
  int64_t mtime_ns = 0;
  bool operator==(const FileIdentity& o) const {
    return inode == o.inode && mtime_ns == o.mtime_ns;
  }
};
FileIdentity Identify(const std::string& path) {
  struct stat st {};
  ::stat(path.c_str(), &st);
  return {st.st_ino, static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
}

// One moment: interrupt, resume, check. Returns whether the first run was
// really interrupted.
bool KillAndResume(const std::string& name, const std::string& crash_at,
                   std::chrono::milliseconds kill_after) {
  SCOPED_TRACE(name);
  const std::string dir = FreshDir("kill_" + name);
  const std::string config = WriteSmallRig(dir);
  const std::string capture = dir + "/c";
  const RunResult first =
      RunHairrig({"capture", "--config", config, "--out", capture}, crash_at, kill_after);
  if (!first.killed) {
    EXPECT_TRUE(crash_at.empty()) << "crash point " << crash_at << " was never reached";
    return false;
  }
  if (!fs::exists(capture + "/journal.jsonl"))
    return true;  // killed before the folder existed: nothing to resume
  const auto before = VerifiedFramesOnDisk(capture);
  std::map<int, FileIdentity> identity;
  for (const auto& [view, r] : before)
    identity[view] = Identify(capture + "/" + r["file"].get<std::string>());
  const size_t records_before = ReadJournal(capture).size();

  const RunResult resumed = RunHairrig({"capture", "--out", capture, "--resume", "--json"}, "", {});
  EXPECT_EQ(resumed.exit_code, 0) << "resume did not complete";
  const auto after = VerifiedFramesOnDisk(capture);
  EXPECT_EQ(after.size(), 38u) << "views verified after resume";
  const auto journal = ReadJournal(capture);
  int frame_records = 0;
  for (const auto& r : journal) frame_records += r.value("event", "") == "frame_stored" ? 1 : 0;
  EXPECT_EQ(frame_records, static_cast<int>(after.size()))
      << "a journalled frame fails to verify, or a view was stored twice";
  for (size_t i = std::min(records_before, journal.size()); i < journal.size(); ++i) {
    const auto& r = journal[i];
    if (r.value("event", "") == "frame_stored") {
      EXPECT_FALSE(before.count(r["view"].get<int>()))
          << "verified view " << r["view"] << " was shot again";
    }
  }
  for (const auto& [view, r] : before) {
    if (!after.count(view)) {
      ADD_FAILURE() << "verified view " << view << " lost by the resume";
      continue;
    }
    EXPECT_EQ(after.at(view)["sha256"], r["sha256"]) << "view " << view;
    EXPECT_TRUE(Identify(capture + "/" + r["file"].get<std::string>()) == identity[view])
        << "view " << view << " touched";
  }
  std::ifstream in(capture + "/manifest.json");
  const auto manifest = nlohmann::json::parse(in);
  EXPECT_EQ(manifest["status"], "complete");
  EXPECT_EQ(manifest["views_completed"], 38);
  return true;
}

TEST(CaptureKillResume, TwentyAndMoreMomentsResumeToACompleteVerifiedCapture) {
  int interrupted = 0;
  for (const char* point : {"frame_half_written", "frame_before_rename", "frame_before_journal",
                            "journal_half_written", "manifest_half_written"}) {
    for (int n : {1, 9, 23, 37}) {
      const std::string name = std::string(point) + "_" + std::to_string(n);
      interrupted += KillAndResume(name, std::string(point) + ":" + std::to_string(n), {}) ? 1 : 0;
    }
  }
  for (int ms : {20, 60, 120, 200, 300, 450}) {
    interrupted +=
        KillAndResume("timed_" + std::to_string(ms) + "ms", "", std::chrono::milliseconds(ms)) ? 1
                                                                                               : 0;
  }
  std::printf("capture interrupted by SIGKILL at %d moments, each resumed and verified\n",
              interrupted);
  EXPECT_GE(interrupted, 20);
}

}  // namespace
}  // namespace hairrig
