#include "sim_hw/sim_dslr_server.h"

#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

#include "sim_hw/scene.h"
#include "sim_hw/sim_devices.h"
#include "sim_hw/sim_dslr_protocol.h"

namespace hairrig {

namespace {
// A body's live-view frames are about this wide (a DSLR streams 640 x 424 or so).
constexpr int kPreviewWidthPx = 640;
}  // namespace

namespace proto = sim_dslr;
using proto::Message;
using Clock = std::chrono::steady_clock;

namespace {

const std::vector<std::string> kShutterSpeeds = {
    "1/4000", "1/2000", "1/1000", "1/500", "1/250", "1/125", "1/100", "1/60",
    "1/50",   "1/30",   "1/15",   "1/8",   "1/4",   "1/2",   "1",     "2"};
const std::vector<std::string> kIsoValues = {"100", "200", "400", "800", "1600", "3200", "6400"};
const std::vector<std::string> kApertures = {"2.8", "4", "5.6", "8", "11", "16"};
const std::vector<std::string> kImageFormats = {"Large Fine JPEG", "Large Normal JPEG"};
const std::vector<std::string> kCaptureTargets = {"Internal RAM", "Memory card"};

// libgphoto2 names folders with or without a trailing slash.
std::string NormalFolder(std::string folder) {
  while (folder.size() > 1 && folder.back() == '/') folder.pop_back();
  return folder;
}

double ShutterSeconds(const std::string& text) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos) return std::stod(text);
  return std::stod(text.substr(0, slash)) / std::stod(text.substr(slash + 1));
}

std::string NearestShutterSpeed(double seconds) {
  std::string best = kShutterSpeeds.front();
  for (const std::string& s : kShutterSpeeds) {
    if (std::abs(std::log(ShutterSeconds(s) / seconds)) <
        std::abs(std::log(ShutterSeconds(best) / seconds)))
      best = s;
  }
  return best;
}

struct StoredFile {
  std::string bytes;
  int64_t mtime_s = 0;
};

// A client connection and the thread serving it.
struct Client {
  int fd = -1;
  uint64_t request_id = 0;  // the id the next reply echoes
  pid_t pid = 0;
  std::thread thread;
  bool done = false;
};

}  // namespace

class SimDslrServer::Impl {
 public:
  Impl(std::shared_ptr<SimWorld> world, SimDslrOptions options, bool owns_folder)
      : world_(std::move(world)), options_(std::move(options)), owns_folder_(owns_folder) {
    const Scene& scene = WorldRenderer(*world_).scene();
    config_ = {
        {"iso", "ISO Speed", "imgsettings", false, "100", kIsoValues},
        {"shutterspeed", "Shutter Speed", "capturesettings", false,
         NearestShutterSpeed(scene.cameras[static_cast<size_t>(options_.scene_camera)].exposure_s),
         kShutterSpeeds},
        {"aperture", "Aperture", "capturesettings", false, "8", kApertures},
        {"imageformat", "Image Format", "imgsettings", false, kImageFormats.front(), kImageFormats},
        {"capturetarget", "Capture Target", "settings", false, kCaptureTargets.front(),
         kCaptureTargets},
        {"serialnumber", "Serial Number", "status", true, options_.serial, {}},
        {"cameramodel", "Camera Model", "status", true, proto::kModel, {}},
        {"manufacturer", "Camera Manufacturer", "status", true, "hairrig", {}},
    };
  }

  Status Listen() {
    socket_path_ = proto::SocketPathForPort(options_.folder);
    if (socket_path_.empty())
      return InvalidArgument("simulated DSLR: folder path too long for a Unix socket: " +
                             options_.folder);
    std::error_code ec;
    std::filesystem::remove(socket_path_, ec);
    listen_fd_ = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, socket_path_.c_str(), socket_path_.size() + 1);
    if (listen_fd_ < 0 ||
        bind(listen_fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0 ||
        listen(listen_fd_, 8) != 0) {
      return IoError("simulated DSLR: cannot listen on " + socket_path_ + ": " +
                     std::strerror(errno));
    }
    accept_thread_ = std::thread([this] { AcceptLoop(); });
    shooter_thread_ = std::thread([this] { ShooterLoop(); });
    if (!options_.trigger_line.empty()) {
      subscription_ =
          WorldTriggers(*world_).Subscribe(options_.trigger_line, [this] { QueueShot(); });
    }
    return Status::Ok();
  }

  ~Impl() { Stop(); }

  void Stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopped_) return;
      stopped_ = true;
      cv_.notify_all();
    }
    if (subscription_ != 0)
      WorldTriggers(*world_).Unsubscribe(options_.trigger_line, subscription_);
    shutdown(listen_fd_, SHUT_RDWR);
    if (accept_thread_.joinable()) accept_thread_.join();
    if (shooter_thread_.joinable()) shooter_thread_.join();
    DropClients();
    close(listen_fd_);
    std::error_code ec;
    std::filesystem::remove(socket_path_, ec);
    if (owns_folder_) std::filesystem::remove_all(options_.folder, ec);
  }

  void InjectFault(Fault fault, int count) {
    std::lock_guard<std::mutex> lock(mutex_);
    injected_[fault] += count;
  }

  const SimDslrOptions& options() const { return options_; }
  int shots() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return shots_;
  }
  int connections() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return connections_;
  }

 private:
  // --- connections -------------------------------------------------------
  void AcceptLoop() {
    for (;;) {
      const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd < 0) {
        if (errno == EINTR || errno == ECONNABORTED) continue;
        return;  // listening socket shut down
      }
      std::lock_guard<std::mutex> lock(mutex_);
      ReapClientsLocked();
      if (stopped_ || gone_connects_left_ > 0) {
        // A camera that dropped off the bus: the connection goes nowhere.
        if (gone_connects_left_ > 0 && --gone_connects_left_ == 0) gone_ = false;
        close(fd);
        continue;
      }
      ++connections_;
      ucred cred{};
      socklen_t len = sizeof(cred);
      getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len);
      auto client = std::make_unique<Client>();
      client->fd = fd;
      client->pid = cred.pid;
      Client* raw = client.get();
      client->thread = std::thread([this, raw] { Serve(raw); });
      clients_.push_back(std::move(client));
    }
  }

  void ReapClientsLocked() {
    for (auto it = clients_.begin(); it != clients_.end();) {
      if (!(*it)->done) {
        ++it;
        continue;
      }
      (*it)->thread.join();
      it = clients_.erase(it);
    }
  }

  void DropClients() {
    std::vector<std::unique_ptr<Client>> clients;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      clients.swap(clients_);
      for (auto& c : clients) shutdown(c->fd, SHUT_RDWR);
      cv_.notify_all();
    }
    for (auto& c : clients) c->thread.join();
  }

  // The camera dropped off the bus (a camera_gone fault): every connection
  // closes, the session's claim goes with the device (it comes back
  // unclaimed, however late the old connection's thread ends), and the next
  // `refused_connects` connections are dropped unanswered.
  void GoneLocked(int refused_connects) {
    gone_ = true;
    owner_ = nullptr;
    gone_connects_left_ = std::max(1, refused_connects);
    for (auto& c : clients_) shutdown(c->fd, SHUT_RDWR);
    cv_.notify_all();
  }

  bool TakeInjectedLocked(Fault fault) {
    auto it = injected_.find(fault);
    if (it == injected_.end() || it->second <= 0) return false;
    --it->second;
    return true;
  }

  void Serve(Client* client) {
    Message request;
    while (proto::ReadMessage(client->fd, -1, &request) == proto::IoResult::kOk) {
      client->request_id = request.id;
      bool reply = true;
      bool hang_up = false;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (TakeInjectedLocked(Fault::kDisconnect))
          hang_up = true;
        else if (TakeInjectedLocked(Fault::kNoReply))
          reply = false;
        else if (TakeInjectedLocked(Fault::kBusy)) {
          Reply(client, {"ERR", proto::kErrBusy, "camera busy (injected)"});
          continue;
        }
      }
      if (hang_up) break;
      if (!reply) continue;
      const bool keep = Dispatch(client, request);
      if (!keep) break;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (owner_ == client) owner_ = nullptr;
    shutdown(client->fd, SHUT_RDWR);
    close(client->fd);
    client->done = true;
  }

  // Answers one request; false ends the connection.
  bool Dispatch(Client* client, const Message& m) {
    const std::string& verb = m.field(0);
    if (verb == "HELLO") return Hello(client);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (owner_ != client) {
        Reply(client, {"ERR", proto::kErrIo, "send HELLO first"});
        return false;
      }
    }
    if (verb == "BYE") {
      // The camera is free before the client hears OK, as a USB release
      // completes before libusb returns: the next HELLO finds it unclaimed.
      {
        std::lock_guard<std::mutex> lock(mutex_);
        owner_ = nullptr;
      }
      Reply(client, {"OK"});
      return false;
    }
    if (verb == "CAPTURE") return Reply(client, CaptureNow());
    if (verb == "TRIGGER") {
      QueueShot();
      return Reply(client, {"OK"});
    }
    if (verb == "PREVIEW") return Preview(client);
    if (verb == "EVENT") return Reply(client, NextEvent(std::atoi(m.field(1).c_str())));
    if (verb == "FOLDERS") return Reply(client, {"OK"}, Folders(NormalFolder(m.field(1))));
    if (verb == "FILES") return Reply(client, {"OK"}, Files(NormalFolder(m.field(1))));
    if (verb == "INFO" || verb == "GET" || verb == "DELETE") {
      return FileRequest(client, verb, NormalFolder(m.field(1)), m.field(2));
    }
    if (verb == "CONFIG") {
      std::lock_guard<std::mutex> lock(mutex_);
      return Reply(client, {"OK"}, proto::EncodeConfig(config_));
    }
    if (verb == "SET") return Reply(client, Set(m.field(1), m.field(2)));
    return Reply(client, {"ERR", proto::kErrBadValue, "unknown request '" + verb + "'"});
  }

  static bool Reply(const Client* client, const std::vector<std::string>& fields,
                    const std::string& payload = {}) {
    return proto::WriteMessage(client->fd, client->request_id, fields, payload) ==
           proto::IoResult::kOk;
  }

  bool Hello(Client* client) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (TakeInjectedLocked(Fault::kClaimed)) {
      lock.unlock();
      Reply(client,
            {"ERR", proto::kErrClaimed, "the camera is claimed by process 4242 (injected)"});
      return false;
    }
    if (owner_ != nullptr && owner_ != client) {
      const std::string holder = std::to_string(owner_->pid);
      lock.unlock();
      Reply(client, {"ERR", proto::kErrClaimed, "the camera is claimed by process " + holder});
      return false;
    }
    if (owner_ != client) {
      // A new session, as a PTP OpenSession: it hears of no file written
      // before it (the files stay on the card).
      ++session_;
      events_.clear();
    }
    owner_ = client;
    lock.unlock();
    return Reply(client,
                 {"OK", proto::kModel, options_.serial, std::to_string(options_.reply_timeout_ms)});
  }

  // --- shooting ------------------------------------------------------------
  struct Shot {
    WorldExposure exposure;
    double exposure_s = 0;
    double gain_db = 0;
    int jpeg_quality = 95;
    bool drop = false;
    double extra_delay_s = 0;
    uint64_t session = 0;  // the session that fired the shutter hears of the file
  };

  // Latches the world and the settings at the shutter; applies world faults.
  // False when the camera has dropped off the bus.
  bool StartShotLocked(Shot* shot) {
    if (gone_) return false;
    shot->session = session_;
    shot->exposure = ExposeWorldNow(*world_);
    shot->exposure_s = ShutterSeconds(ValueLocked("shutterspeed"));
    shot->gain_db = 20.0 * std::log10(std::stod(ValueLocked("iso")) / 100.0);
    shot->jpeg_quality = ValueLocked("imageformat") == "Large Normal JPEG" ? 85 : 95;
    const SimFault* fault = NextCameraFault(*world_, options_.serial);
    if (fault && fault->kind == SimFaultKind::kCameraGone) {
      GoneLocked(fault->count);
      return false;
    }
    if (fault && fault->kind == SimFaultKind::kDropFrame) shot->drop = true;
    if (fault && fault->kind == SimFaultKind::kDownloadTimeout)
      shot->extra_delay_s = fault->delay_s;
    return true;
  }

  // Renders, waits out exposure, readout and download, stores the file.
  // Returns its name, or "" for a dropped shot.
  Result<std::string> Develop(const Shot& shot) {
    const auto t0 = Clock::now();
    const uint64_t sequence = static_cast<uint64_t>(shots());
    HR_ASSIGN_OR_RETURN(
        cv::Mat image,
        RenderWorldExposure(*world_, options_.scene_camera, shot.exposure, shot.exposure_s,
                            shot.gain_db, FrameNoiseSeed(*world_, options_.serial, sequence)));
    std::vector<uint8_t> jpeg;
    if (!cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, shot.jpeg_quality})) {
      return Internal("simulated DSLR " + options_.serial + ": JPEG encoding failed");
    }
    const Scene& scene = WorldRenderer(*world_).scene();
    const double device_s =
        shot.exposure_s + scene.camera_readout_s + scene.camera_download_s + shot.extra_delay_s;
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_until(lock,
                   t0 + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double>(device_s * WorldTimeScale(*world_))),
                   [this] { return stopped_; });
    if (shot.drop) return std::string();
    char name[32];
    std::snprintf(name, sizeof(name), "IMG_%04d.JPG", ++shots_);
    card_[name] = {std::string(jpeg.begin(), jpeg.end()),
                   std::chrono::duration_cast<std::chrono::seconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count()};
    return std::string(name);
  }

  // The live view: the world now, at the shot's settings, scaled to a body's
  // live-view size (kPreviewWidthPx wide), as a JPEG; no shot is counted.
  bool Preview(const Client* client) {
    Shot shot;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!StartShotLocked(&shot))
        return Reply(client, {"ERR", proto::kErrIo, "the camera dropped off the bus"});
    }
    Result<cv::Mat> image =
        RenderWorldExposure(*world_, options_.scene_camera, shot.exposure, shot.exposure_s,
                            shot.gain_db, FrameNoiseSeed(*world_, options_.serial, ++previews_));
    if (!image.ok()) return Reply(client, {"ERR", proto::kErrIo, image.status().message()});
    cv::Mat small;
    const double scale = std::min(1.0, static_cast<double>(kPreviewWidthPx) / image->cols);
    cv::resize(*image, small, cv::Size(), scale, scale, cv::INTER_AREA);
    std::vector<uint8_t> jpeg;
    if (!cv::imencode(".jpg", small, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80}))
      return Reply(client, {"ERR", proto::kErrIo, "live view: JPEG encoding failed"});
    return Reply(client, {"OK"}, std::string(jpeg.begin(), jpeg.end()));
  }

  std::vector<std::string> CaptureNow() {
    Shot shot;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!StartShotLocked(&shot)) return {"ERR", proto::kErrIo, "the camera dropped off the bus"};
    }
    Result<std::string> name = Develop(shot);
    if (!name.ok()) return {"ERR", proto::kErrIo, name.status().message()};
    // A dropped shot: the camera fired but wrote nothing (a real body may do
    // this when the card stalls); the client sees the capture fail.
    if (name->empty()) return {"ERR", proto::kErrIo, "the shot was not written (dropped frame)"};
    return {"OK", proto::kImageFolder, *name};
  }

  void QueueShot() {
    std::lock_guard<std::mutex> lock(mutex_);
    Shot shot;
    if (!StartShotLocked(&shot)) return;
    pending_shots_.push_back(shot);
    cv_.notify_all();
  }

  void ShooterLoop() {
    for (;;) {
      Shot shot;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return stopped_ || !pending_shots_.empty(); });
        if (stopped_) return;
        shot = pending_shots_.front();
        pending_shots_.pop_front();
      }
      Result<std::string> name = Develop(shot);
      std::lock_guard<std::mutex> lock(mutex_);
      if (name.ok() && !name->empty() && shot.session == session_) {
        events_.push_back(*name);
        cv_.notify_all();
      }
    }
  }

  std::vector<std::string> NextEvent(int timeout_ms) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait_for(lock, std::chrono::milliseconds(std::max(0, timeout_ms)),
                 [this] { return stopped_ || gone_ || !events_.empty(); });
    if (gone_ || stopped_) return {"ERR", proto::kErrIo, "the camera dropped off the bus"};
    if (events_.empty()) return {"OK", "TIMEOUT"};
    const std::string name = events_.front();
    events_.pop_front();
    return {"OK", "FILE_ADDED", proto::kImageFolder, name};
  }

  // --- storage ---------------------------------------------------------------
  static std::string Folders(const std::string& folder) {
    if (folder == "/") return "store_00010001\n";
    if (folder == proto::kStorageFolder) return "DCIM\n";
    if (folder == std::string(proto::kStorageFolder) + "/DCIM") return "100HRSIM\n";
    return "";
  }

  std::string Files(const std::string& folder) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string out;
    if (folder != proto::kImageFolder) return out;
    for (const auto& [name, file] : card_) out += name + "\n";
    return out;
  }

  bool FileRequest(const Client* client, const std::string& verb, const std::string& folder,
                   const std::string& name) {
    std::unique_lock<std::mutex> lock(mutex_);
    auto it = card_.find(name);
    if (folder != proto::kImageFolder || it == card_.end()) {
      lock.unlock();
      return Reply(client, {"ERR", proto::kErrNotFound,
                            "no file " + folder + "/" + name + " on the camera"});
    }
    if (verb == "INFO") {
      const std::vector<std::string> fields = {"OK", std::to_string(it->second.bytes.size()),
                                               std::to_string(it->second.mtime_s)};
      lock.unlock();
      return Reply(client, fields);
    }
    if (verb == "DELETE") {
      card_.erase(it);
      lock.unlock();
      return Reply(client, {"OK"});
    }
    std::string bytes = it->second.bytes;
    // Internal RAM holds a shot only until it has been downloaded.
    if (ValueLocked("capturetarget") == "Internal RAM") card_.erase(it);
    lock.unlock();
    return Reply(client, {"OK"}, bytes);
  }

  // --- configuration ---------------------------------------------------------
  std::string ValueLocked(const std::string& name) const {
    for (const auto& item : config_) {
      if (item.name == name) return item.value;
    }
    return "";
  }

  std::vector<std::string> Set(const std::string& name, const std::string& value) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto& item : config_) {
      if (item.name != name) continue;
      if (item.read_only) return {"ERR", proto::kErrBadValue, name + " is read-only"};
      if (std::find(item.choices.begin(), item.choices.end(), value) == item.choices.end()) {
        std::string list;
        for (const auto& c : item.choices) list += (list.empty() ? "" : ", ") + c;
        return {"ERR", proto::kErrBadValue,
                "'" + value + "' is not a choice of " + name + " (" + list + ")"};
      }
      item.value = value;
      return {"OK"};
    }
    return {"ERR", proto::kErrBadValue, "no setting named " + name};
  }

  std::shared_ptr<SimWorld> world_;
  SimDslrOptions options_;
  bool owns_folder_;
  std::string socket_path_;
  int listen_fd_ = -1;
  std::thread accept_thread_;
  std::thread shooter_thread_;
  int subscription_ = 0;

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  bool stopped_ = false;
  std::vector<std::unique_ptr<Client>> clients_;
  Client* owner_ = nullptr;  // the client that said HELLO and holds the camera
  std::vector<proto::ConfigItem> config_;
  std::map<std::string, StoredFile> card_;
  std::deque<Shot> pending_shots_;
  std::deque<std::string> events_;
  uint64_t session_ = 0;  // counts the sessions opened (HELLO from a new owner)
  std::map<Fault, int> injected_;
  bool gone_ = false;
  int gone_connects_left_ = 0;
  int shots_ = 0;
  std::atomic<uint64_t> previews_{0};  // live-view frames served (their noise seeds)
  int connections_ = 0;
};

Result<std::string> SimDslrCamlibFolder() {
  const char* env = std::getenv("HAIRRIG_CAMLIBS");
  const std::string folder = env != nullptr && *env != '\0' ? env : HAIRRIG_CAMLIB_DIR;
  if (!std::filesystem::exists(std::filesystem::path(folder) / "hairrig_sim_dslr.so")) {
    return NotFound(
        folder +
        " has no hairrig_sim_dslr.so, the simulated DSLR's camlib: build it (ninja -C build "
        "hairrig_sim_dslr) or point HAIRRIG_CAMLIBS at the folder holding it");
  }
  return folder;
}

Status ExportSimDslrCamlibs() {
  HR_ASSIGN_OR_RETURN(const std::string folder, SimDslrCamlibFolder());
  const char* current = std::getenv("CAMLIBS");
  if (current != nullptr && *current != '\0' && std::string(current) != folder) {
    if (!std::filesystem::exists(std::filesystem::path(current) / "hairrig_sim_dslr.so")) {
      return InvalidArgument(std::string("CAMLIBS is set to ") + current +
                             ", which lacks hairrig_sim_dslr.so: unset CAMLIBS, or set it to " +
                             folder);
    }
    return Status::Ok();
  }
  setenv("CAMLIBS", folder.c_str(), 1);
  return Status::Ok();
}

namespace {

constexpr char kFolderPrefix[] = "hairrig-dslr-";
constexpr char kOwnerFile[] = "owner.pid";

// Whether something accepts connections on the Unix socket at `path`.
bool SocketListens(const std::string& path) {
  sockaddr_un address{};
  if (path.size() >= sizeof address.sun_path) return false;
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  const bool listens =
      fd >= 0 && connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0;
  if (fd >= 0) close(fd);
  return listens;
}

// The process named in `folder`'s owner file; 0 when there is none.
pid_t FolderOwner(const std::filesystem::path& folder) {
  std::ifstream in(folder / kOwnerFile);
  long pid = 0;
  if (!(in >> pid) || pid <= 0) return 0;
  return static_cast<pid_t>(pid);
}

bool IsStaleFolder(const std::filesystem::path& folder) {
  struct stat info {};
  if (lstat(folder.c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || info.st_uid != getuid())
    return false;
  const pid_t owner = FolderOwner(folder);
  if (owner == 0 || kill(owner, 0) == 0 || errno != ESRCH) return false;
  return !SocketListens((folder / proto::kSocketName).string());
}

}  // namespace

int RemoveStaleSimDslrFolders(const std::string& parent) {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(parent, ec)) {
    if (entry.path().filename().string().rfind(kFolderPrefix, 0) != 0 ||
        !IsStaleFolder(entry.path()))
      continue;
    std::error_code remove_error;
    std::filesystem::remove_all(entry.path(), remove_error);
    if (!remove_error) ++removed;
  }
  return removed;
}

Status SimDslrOptions::Check() const {
  if (serial.empty()) return InvalidArgument("serial (the camera's serial number) is required");
  if (scene_camera < 0) {
    return InvalidArgument("scene_camera must be 0 or more, got " + std::to_string(scene_camera));
  }
  if (reply_timeout_ms < 1) {
    return InvalidArgument("reply_timeout_ms must be at least 1, got " +
                           std::to_string(reply_timeout_ms));
  }
  return Status::Ok();
}

Result<std::unique_ptr<SimDslrServer>> SimDslrServer::Start(std::shared_ptr<SimWorld> world,
                                                            SimDslrOptions options) {
  HR_RETURN_IF_ERROR(options.Check().WithContext("simulated DSLR"));
  const Scene& scene = WorldRenderer(*world).scene();
  if (options.scene_camera < 0 || options.scene_camera >= static_cast<int>(scene.cameras.size())) {
    return InvalidArgument("simulated DSLR " + options.serial + ": the scene has no camera " +
                           std::to_string(options.scene_camera));
  }
  bool owns_folder = false;
  if (options.folder.empty()) {
    const std::filesystem::path parent = std::filesystem::temp_directory_path();
    RemoveStaleSimDslrFolders(parent.string());
    std::string pattern = (parent / (std::string(kFolderPrefix) + "XXXXXX")).string();
    if (mkdtemp(pattern.data()) == nullptr) {
      return IoError("simulated DSLR " + options.serial + ": cannot make a folder under " +
                     parent.string() + ": " + std::strerror(errno));
    }
    options.folder = pattern;
    owns_folder = true;
    std::ofstream(std::filesystem::path(pattern) / kOwnerFile) << getpid() << "\n";
  } else {
    std::error_code ec;
    std::filesystem::create_directories(options.folder, ec);
    if (ec)
      return IoError("simulated DSLR " + options.serial + ": cannot make " + options.folder + ": " +
                     ec.message());
  }
  auto impl = std::make_unique<Impl>(std::move(world), std::move(options), owns_folder);
  HR_RETURN_IF_ERROR(impl->Listen());
  return std::unique_ptr<SimDslrServer>(new SimDslrServer(std::move(impl)));
}

SimDslrServer::SimDslrServer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SimDslrServer::~SimDslrServer() { Stop(); }
const std::string& SimDslrServer::folder() const { return impl_->options().folder; }
const std::string& SimDslrServer::serial() const { return impl_->options().serial; }
std::string SimDslrServer::Describe() const {
  return "simulated DSLR " + serial() + " at " + port();
}
void SimDslrServer::InjectFault(Fault fault, int count) { impl_->InjectFault(fault, count); }
int SimDslrServer::shots() const { return impl_->shots(); }
int SimDslrServer::connections() const { return impl_->connections(); }
void SimDslrServer::Stop() { impl_->Stop(); }

}  // namespace hairrig
