#include "core/file_util.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

namespace hairrig {

void ScopedFd::reset(int fd) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = fd;
}

namespace {

const char* FileKind(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

Status TooLarge(const std::string& path, uint64_t max_bytes) {
  return OutOfRange(path + ": larger than " + std::to_string(max_bytes) +
                    " bytes, the most this reader accepts");
}

// Opens `path` for reading if it is a regular file of at most `max_bytes`;
// *size is its length. O_NONBLOCK: opening a FIFO with no writer returns at once.
Status OpenRegularFile(const std::string& path, uint64_t max_bytes, ScopedFd* fd, uint64_t* size) {
  fd->reset(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY));
  if (fd->get() < 0) {
    const std::string why = std::strerror(errno);
    if (errno == ENOENT) return NotFound(path + ": cannot open for reading (" + why + ")");
    return IoError(path + ": cannot open for reading (" + why + ")");
  }
  struct stat st {};
  if (::fstat(fd->get(), &st) != 0)
    return IoError(path + ": cannot read its file status (" + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode))
    return InvalidArgument(path + " is " + FileKind(st.st_mode) + ", not a regular file");
  *size = static_cast<uint64_t>(st.st_size);
  if (*size > max_bytes) return TooLarge(path, max_bytes);
  return Status::Ok();
}

// Writes all `size` bytes through `write_call` (::write when empty), retrying
// on EINTR and after short writes.
Status WriteAll(int fd, const std::string& path, const uint8_t* p, size_t size,
                const WriteCall& write_call) {
  while (size > 0) {
    const ssize_t n = write_call ? write_call(fd, p, size) : ::write(fd, p, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return IoErrorFromErrno(path + ": write failed", errno);
    }
    p += n;
    size -= static_cast<size_t>(n);
  }
  return Status::Ok();
}

// WriteAll in two parts, with on_stage("half_written") between them.
Status WriteInHalves(int fd, const std::string& path, const void* bytes, size_t size,
                     const StageHook& on_stage, const WriteCall& write_call) {
  const auto* p = static_cast<const uint8_t*>(bytes);
  const size_t first = size - size / 2;
  HR_RETURN_IF_ERROR(WriteAll(fd, path, p, first, write_call));
  if (on_stage) on_stage("half_written");
  return WriteAll(fd, path, p + first, size - first, write_call);
}

}  // namespace

Result<int> OpenRegularFileForAppend(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISLNK(st.st_mode))
    return InvalidArgument(path + " is " + FileKind(st.st_mode) + ", not a regular file");
  // O_NONBLOCK: should a FIFO take the checked name meanwhile, opening it fails at once.
  ScopedFd fd;
  fd.reset(::open(path.c_str(),
                  O_WRONLY | O_CREAT | O_APPEND | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK | O_NOCTTY,
                  0644));
  if (fd.get() < 0) return IoErrorFromErrno(path + ": cannot open for appending", errno);
  if (::fstat(fd.get(), &st) != 0)
    return IoErrorFromErrno(path + ": cannot read its file status", errno);
  if (!S_ISREG(st.st_mode))
    return InvalidArgument(path + " is " + FileKind(st.st_mode) + ", not a regular file");
  const int flags = ::fcntl(fd.get(), F_GETFL);
  if (flags < 0 || ::fcntl(fd.get(), F_SETFL, flags & ~O_NONBLOCK) != 0)
    return IoErrorFromErrno(path + ": cannot set blocking writes", errno);
  const int opened = fd.get();
  fd.release();
  return opened;
}

Result<int> OpenRegularFileForRead(const std::string& path, uint64_t max_bytes) {
  ScopedFd fd;
  uint64_t size = 0;
  HR_RETURN_IF_ERROR(OpenRegularFile(path, max_bytes, &fd, &size));
  const int opened = fd.get();
  fd.release();
  return opened;
}

Status ReadFileChunks(const std::string& path, uint64_t max_bytes,
                      const std::function<void(const uint8_t* data, size_t size)>& chunk) {
  ScopedFd fd;
  uint64_t size = 0;
  HR_RETURN_IF_ERROR(OpenRegularFile(path, max_bytes, &fd, &size));
  std::vector<uint8_t> buffer(size_t{1} << 16);
  uint64_t total = 0;
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer.data(), buffer.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return IoError(path + ": read failed (" + std::strerror(errno) + ")");
    }
    if (n == 0) return Status::Ok();
    total += static_cast<uint64_t>(n);
    if (total > max_bytes) return TooLarge(path, max_bytes);  // it grew while being read
    chunk(buffer.data(), static_cast<size_t>(n));
  }
}

Result<std::vector<uint8_t>> ReadFileBytes(const std::string& path, uint64_t max_bytes) {
  std::vector<uint8_t> bytes;
  HR_RETURN_IF_ERROR(ReadFileChunks(path, max_bytes, [&bytes](const uint8_t* data, size_t size) {
    bytes.insert(bytes.end(), data, data + size);
  }));
  return bytes;
}

Result<std::string> ReadFileText(const std::string& path, uint64_t max_bytes) {
  std::string text;
  HR_RETURN_IF_ERROR(ReadFileChunks(path, max_bytes, [&text](const uint8_t* data, size_t size) {
    text.append(reinterpret_cast<const char*>(data), size);
  }));
  return text;
}

Status SyncFolder(const std::string& folder) {
  const int fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0)
    return IoError(folder + ": cannot open the folder to sync it (" + std::strerror(errno) + ")");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) return IoError(folder + ": fsync failed (" + std::strerror(errno) + ")");
  return Status::Ok();
}

Status IoErrorFromErrno(const std::string& what, int error_number) {
  return IoError(what + " (" + std::strerror(error_number) + ")");
}

Status WriteFileAtomic(const std::string& path, const void* bytes, size_t size,
                       const StageHook& on_stage, const WriteCall& write_call) {
  // Unique per process and per call, so that two threads writing one path never share a temporary.
  static std::atomic<uint64_t> next_temporary{0};
  const std::string tmp =
      path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(next_temporary++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) return IoErrorFromErrno(tmp + ": cannot create", errno);
  Status s = WriteInHalves(fd, path, bytes, size, on_stage, write_call);
  if (s.ok() && ::fsync(fd) != 0) s = IoErrorFromErrno(path + ": fsync failed", errno);
  if (::close(fd) != 0 && s.ok()) s = IoErrorFromErrno(path + ": close failed", errno);
  if (!s.ok()) {
    ::unlink(tmp.c_str());
    return s;
  }
  if (on_stage) on_stage("before_rename");
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int error_number = errno;
    ::unlink(tmp.c_str());
    return IoErrorFromErrno(path + ": rename into place failed", error_number);
  }
  const size_t slash = path.find_last_of('/');
  return SyncFolder(slash == std::string::npos ? "." : path.substr(0, slash == 0 ? 1 : slash));
}

Status AppendDurably(int fd, const std::string& path, const void* bytes, size_t size,
                     const StageHook& on_stage, const WriteCall& write_call) {
  struct stat before {};
  if (::fstat(fd, &before) != 0)
    return IoErrorFromErrno(path + ": cannot read its file status", errno);
  Status s = WriteInHalves(fd, path, bytes, size, on_stage, write_call);
  if (s.ok() && ::fdatasync(fd) != 0) s = IoErrorFromErrno(path + ": fsync failed", errno);
  if (!s.ok() && ::ftruncate(fd, before.st_size) != 0) {
    return IoErrorFromErrno(s.message() + "; cutting the file back to its former length failed too",
                            errno);
  }
  return s;
}

std::string FileExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool PathIsInside(const std::string& path, const std::string& folder) {
  namespace fs = std::filesystem;
  const fs::path p = fs::absolute(path).lexically_normal();
  const fs::path f = fs::absolute(folder).lexically_normal();
  const fs::path rel = p.lexically_relative(f);
  return !rel.empty() && *rel.begin() != ".." && rel.is_relative() && rel != ".";
}

Result<std::string> ResolveInside(const std::string& path, const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) return IoError(path + ": cannot resolve the path (" + ec.message() + ")");
  const fs::path root = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  if (ec) return IoError(folder + ": cannot resolve the path (" + ec.message() + ")");
  if (!PathIsInside(resolved.string(), root.string()))
    return CorruptData(path + " leads to " + resolved.string() + ", outside " + root.string());
  return resolved.string();
}

}  // namespace hairrig
