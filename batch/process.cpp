#include "batch/process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#include "core/file_util.h"

extern char** environ;

namespace hairrig {
namespace {

// Closes a file descriptor when it goes out of scope.
class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { Reset(); }
  int get() const { return fd_; }
  void Reset(int fd = -1) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
  }

 private:
  int fd_ = -1;
};

class FileActions {
 public:
  FileActions() { ::posix_spawn_file_actions_init(&actions_); }
  FileActions(const FileActions&) = delete;
  FileActions& operator=(const FileActions&) = delete;
  ~FileActions() { ::posix_spawn_file_actions_destroy(&actions_); }
  posix_spawn_file_actions_t* get() { return &actions_; }

 private:
  posix_spawn_file_actions_t actions_;
};

struct Pipe {
  Fd read_end, write_end;
};

Status MakePipe(Pipe* pipe) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return IoErrorFromErrno("pipe2", errno);
  pipe->read_end.Reset(fds[0]);
  pipe->write_end.Reset(fds[1]);
  return Status::Ok();
}

// Reads both pipes to their end, keeping at most `max_bytes` of each.
Status DrainPipes(int out_fd, int err_fd, size_t max_bytes, std::string* out, std::string* err) {
  std::array<pollfd, 2> fds{pollfd{out_fd, POLLIN, 0}, pollfd{err_fd, POLLIN, 0}};
  std::array<std::string*, 2> sinks{out, err};
  int open_count = 2;
  std::array<char, 65536> buffer;
  while (open_count > 0) {
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      return IoErrorFromErrno("poll on a child's output", errno);
    }
    for (size_t k = 0; k < fds.size(); ++k) {
      if (fds[k].fd < 0 || fds[k].revents == 0) continue;
      const ssize_t n = ::read(fds[k].fd, buffer.data(), buffer.size());
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        fds[k].fd = -1;
        --open_count;
        continue;
      }
      std::string& sink = *sinks[k];
      if (sink.size() < max_bytes)
        sink.append(buffer.data(), std::min(static_cast<size_t>(n), max_bytes - sink.size()));
    }
  }
  return Status::Ok();
}

Result<int> WaitForChild(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return IoErrorFromErrno("waitpid", errno);
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

std::vector<char*> ArgvPointers(const std::vector<std::string>& argv) {
  std::vector<char*> pointers;
  for (const std::string& arg : argv) pointers.push_back(const_cast<char*>(arg.c_str()));
  pointers.push_back(nullptr);
  return pointers;
}

std::string LastLine(const std::string& text) {
  const size_t end = text.find_last_not_of("\n\r ");
  if (end == std::string::npos) return "";
  const size_t start = text.rfind('\n', end);
  return text.substr(start == std::string::npos ? 0 : start + 1,
                     end + 1 - (start == std::string::npos ? 0 : start + 1));
}

}  // namespace

std::string ProcessResult::Describe() const {
  const std::string line = LastLine(err.empty() ? out : err);
  return line.empty() ? "exit code " + std::to_string(exit_code) : line;
}

Result<ProcessResult> RunProcess(const std::vector<std::string>& argv,
                                 const ProcessOptions& options) {
  HR_RETURN_IF_ERROR(options.Check());
  if (argv.empty() || argv[0].empty()) return InvalidArgument("RunProcess: no program given");
  FileActions actions;
  ::posix_spawn_file_actions_addopen(actions.get(), STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  Pipe out, err;
  Fd log_file;
  if (options.output_file.empty()) {
    HR_RETURN_IF_ERROR(MakePipe(&out));
    HR_RETURN_IF_ERROR(MakePipe(&err));
    ::posix_spawn_file_actions_adddup2(actions.get(), out.write_end.get(), STDOUT_FILENO);
    ::posix_spawn_file_actions_adddup2(actions.get(), err.write_end.get(), STDERR_FILENO);
  } else {
    // Opened here, so a file that cannot be written is reported by name.
    log_file.Reset(
        ::open(options.output_file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644));
    if (log_file.get() < 0)
      return IoErrorFromErrno(options.output_file + ": cannot open the log file", errno);
    ::posix_spawn_file_actions_adddup2(actions.get(), log_file.get(), STDOUT_FILENO);
    ::posix_spawn_file_actions_adddup2(actions.get(), log_file.get(), STDERR_FILENO);
  }
  if (!options.working_dir.empty()) {
    ::posix_spawn_file_actions_addchdir_np(actions.get(), options.working_dir.c_str());
  }
  std::vector<char*> args = ArgvPointers(argv);
  pid_t pid = -1;
  const int spawn_error =
      ::posix_spawnp(&pid, argv[0].c_str(), actions.get(), nullptr, args.data(), environ);
  if (spawn_error != 0) {
    const std::string where = options.working_dir.empty() ? "" : " in " + options.working_dir;
    return NotFound(argv[0] + ": cannot be started" + where + " (" + std::strerror(spawn_error) +
                    "); is it installed and on PATH?");
  }
  out.write_end.Reset();
  err.write_end.Reset();
  log_file.Reset();
  ProcessResult result;
  Status drained = Status::Ok();
  if (options.output_file.empty()) {
    drained = DrainPipes(out.read_end.get(), err.read_end.get(), options.max_capture_bytes,
                         &result.out, &result.err);
  }
  HR_ASSIGN_OR_RETURN(result.exit_code, WaitForChild(pid));
  HR_RETURN_IF_ERROR(drained);
  return result;
}

std::string ShellQuote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  return quoted + "'";
}

Result<std::string> SelfExecutable() {
  std::array<char, PATH_MAX> path;
  const ssize_t n = ::readlink("/proc/self/exe", path.data(), path.size() - 1);
  if (n <= 0)
    return IoErrorFromErrno("/proc/self/exe: cannot read the running program's path", errno);
  return std::string(path.data(), static_cast<size_t>(n));
}

namespace {

// The fields of /proc/<pid>/stat after the command name: state is [0], starttime [19].
std::vector<std::string> StatFieldsAfterName(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t name_end = text.rfind(')');
  if (name_end == std::string::npos) return {};
  std::istringstream rest(text.substr(name_end + 1));
  std::vector<std::string> fields;
  for (std::string field; rest >> field;) fields.push_back(field);
  return fields;
}

}  // namespace

uint64_t ProcessStartTicks(pid_t pid) {
  const std::vector<std::string> fields = StatFieldsAfterName(pid);
  if (fields.size() < 20) return 0;
  return std::strtoull(fields[19].c_str(), nullptr, 10);
}

bool ProcessRuns(pid_t pid, uint64_t start_ticks) {
  const std::vector<std::string> fields = StatFieldsAfterName(pid);
  if (fields.size() < 20 || fields[0] == "Z" || fields[0] == "X") return false;
  return std::strtoull(fields[19].c_str(), nullptr, 10) == start_ticks;
}

}  // namespace hairrig
