#include "drivers/gphoto2_camera.h"

#include <gphoto2/gphoto2.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <thread>

#include "core/config.h"
#include "core/log.h"
#include "drivers/camera_support.h"

namespace hairrig {
namespace {

using Clock = std::chrono::steady_clock;

// --- libgphoto2 handles ------------------------------------------------------

// A GPContext that keeps the last error text libgphoto2 or the camlib reported.
class Gphoto2Context {
 public:
  Gphoto2Context() : context_(gp_context_new()) {
    gp_context_set_error_func(context_, &Gphoto2Context::OnError, this);
  }
  ~Gphoto2Context() { gp_context_unref(context_); }
  Gphoto2Context(const Gphoto2Context&) = delete;
  Gphoto2Context& operator=(const Gphoto2Context&) = delete;
  GPContext* get() const { return context_; }
  // The text reported since the last call, then cleared.
  std::string TakeError() { return std::exchange(last_error_, std::string()); }

 private:
  static void OnError(GPContext*, const char* text, void* data) {
    static_cast<Gphoto2Context*>(data)->last_error_ = text ? text : "";
  }
  GPContext* context_;
  std::string last_error_;
};

struct ListDeleter {
  void operator()(CameraList* l) const { gp_list_free(l); }
};
using ListPtr = std::unique_ptr<CameraList, ListDeleter>;

ListPtr NewList() {
  CameraList* list = nullptr;
  gp_list_new(&list);
  return ListPtr(list);
}

struct WidgetDeleter {
  void operator()(CameraWidget* w) const { gp_widget_free(w); }
};
using WidgetPtr = std::unique_ptr<CameraWidget, WidgetDeleter>;

struct FileDeleter {
  void operator()(CameraFile* f) const { gp_file_unref(f); }
};

// The abilities and port lists, loaded once per CAMLIBS folder: loading them
// opens every camlib, which takes tens of milliseconds.
class Gphoto2Catalog {
 public:
  static Result<Gphoto2Catalog*> Get() {
    static std::mutex mutex;
    static std::unique_ptr<Gphoto2Catalog> catalog;
    static std::string loaded_for;
    std::lock_guard<std::mutex> lock(mutex);
    const char* camlibs = std::getenv("CAMLIBS");
    const std::string key = camlibs ? camlibs : "";
    if (catalog && loaded_for == key) return catalog.get();
    auto fresh = std::unique_ptr<Gphoto2Catalog>(new Gphoto2Catalog());
    Gphoto2Context context;
    if (gp_abilities_list_load(fresh->abilities, context.get()) < GP_OK ||
        gp_port_info_list_load(fresh->ports) < GP_OK) {
      return IoError("libgphoto2: cannot load its camera drivers or port drivers (CAMLIBS=" + key +
                     "); is libgphoto2 installed (scripts/install-deps)?");
    }
    catalog =
        std::move(fresh);  // frees the previous one: open cameras hold copies of what they use
    loaded_for = key;
    return catalog.get();
  }
  ~Gphoto2Catalog() {
    gp_abilities_list_free(abilities);
    gp_port_info_list_free(ports);
  }
  CameraAbilitiesList* abilities = nullptr;
  GPPortInfoList* ports = nullptr;

 private:
  Gphoto2Catalog() {
    gp_abilities_list_new(&abilities);
    gp_port_info_list_new(&ports);
  }
};

std::string ResultText(int result) { return gp_result_as_string(result); }

// Turns a libgphoto2 result into a Status whose message says what to do.
Status Gphoto2Status(int result, const std::string& what, const std::string& detail) {
  const std::string reported =
      detail.empty() ? ResultText(result) : detail + " (" + ResultText(result) + ")";
  const std::string text = what + ": " + reported;
  switch (result) {
    case GP_ERROR_IO_USB_CLAIM:
    case GP_ERROR_IO_LOCK:
      return Unavailable(
          text +
          "; another process holds the camera: close gphoto2, Shotwell or digiKam, or stop "
          "gvfs (`pkill -f gvfs-gphoto2-volume-monitor`), then retry");
    case GP_ERROR_CAMERA_BUSY:
      return DeviceFault(text +
                         "; the camera is busy (focusing, writing to its card, or a menu is open)");
    case GP_ERROR_TIMEOUT:
      return Timeout(text + "; the camera did not answer in time");
    case GP_ERROR_IO:
    case GP_ERROR_IO_USB_FIND:
    case GP_ERROR_IO_READ:
    case GP_ERROR_IO_WRITE:
    case GP_ERROR_MODEL_NOT_FOUND:
    case GP_ERROR_CAMERA_ERROR:
      return Unavailable(
          text +
          "; the camera dropped off the bus: check its cable, battery and auto power-off, "
          "then reopen it");
    case GP_ERROR_BAD_PARAMETERS:
      return InvalidArgument(text);
    case GP_ERROR_CORRUPTED_DATA:
      return CorruptData(text);
    case GP_ERROR_FILE_NOT_FOUND:
    case GP_ERROR_DIRECTORY_NOT_FOUND:
      return NotFound(text);
    default:
      return IoError(text);
  }
}

// An open libgphoto2 camera at one port.
class Gphoto2Session {
 public:
  ~Gphoto2Session() {
    if (camera_ != nullptr) {
      gp_camera_exit(camera_, context_.get());
      gp_camera_unref(camera_);
    }
  }

  static Result<std::unique_ptr<Gphoto2Session>> Open(const std::string& model,
                                                      const std::string& port) {
    HR_ASSIGN_OR_RETURN(Gphoto2Catalog * catalog, Gphoto2Catalog::Get());
    auto session = std::unique_ptr<Gphoto2Session>(new Gphoto2Session());
    const std::string where = "camera '" + model + "' at " + port;
    const int model_index = gp_abilities_list_lookup_model(catalog->abilities, model.c_str());
    if (model_index < GP_OK) {
      return NotFound(where + ": libgphoto2 has no driver for this model (CAMLIBS=" +
                      std::string(std::getenv("CAMLIBS") ? std::getenv("CAMLIBS") : "default") +
                      "); `gphoto2 --list-cameras` lists the models it knows");
    }
    const int port_index = gp_port_info_list_lookup_path(catalog->ports, port.c_str());
    if (port_index < GP_OK) {
      return NotFound(
          where +
          ": no such port; `gphoto2 --list-ports` lists the ports, `gphoto2 --auto-detect` "
          "the cameras on them");
    }
    CameraAbilities abilities;
    GPPortInfo port_info;
    gp_abilities_list_get_abilities(catalog->abilities, model_index, &abilities);
    gp_port_info_list_get_info(catalog->ports, port_index, &port_info);
    gp_camera_new(&session->camera_);
    gp_camera_set_abilities(session->camera_, abilities);
    gp_camera_set_port_info(session->camera_, port_info);
    const int r = gp_camera_init(session->camera_, session->context_.get());
    if (r < GP_OK) return Gphoto2Status(r, where + ": cannot open", session->context_.TakeError());
    session->model_ = model;
    session->port_ = port;
    return session;
  }

  Status Check(int result, const std::string& what) {
    last_result_ = result;
    if (result >= GP_OK) return Status::Ok();
    return Gphoto2Status(result, what, context_.TakeError());
  }

  // The libgphoto2 result of the last Check(): tells a busy body from other faults.
  int last_result() const { return last_result_; }

  Result<WidgetPtr> GetSetting(const std::string& name) {
    CameraWidget* widget = nullptr;
    const int r = gp_camera_get_single_config(camera_, name.c_str(), &widget, context_.get());
    last_result_ = r;
    if (r == GP_ERROR_BAD_PARAMETERS || r == GP_ERROR_NOT_SUPPORTED) {
      return NotFound("the camera has no setting named '" + name +
                      "' (`gphoto2 --list-config` lists them)");
    }
    HR_RETURN_IF_ERROR(Check(r, "reading setting " + name));
    return WidgetPtr(widget);
  }

  Result<std::string> ReadText(const std::string& name) {
    HR_ASSIGN_OR_RETURN(WidgetPtr widget, GetSetting(name));
    CameraWidgetType type;
    gp_widget_get_type(widget.get(), &type);
    if (type != GP_WIDGET_TEXT && type != GP_WIDGET_RADIO && type != GP_WIDGET_MENU) {
      return InvalidArgument("setting " + name + " is not text");
    }
    const char* value = nullptr;
    gp_widget_get_value(widget.get(), &value);
    return std::string(value ? value : "");
  }

  static std::vector<std::string> Choices(CameraWidget* widget) {
    std::vector<std::string> choices;
    for (int i = 0; i < gp_widget_count_choices(widget); ++i) {
      const char* c = nullptr;
      gp_widget_get_choice(widget, i, &c);
      choices.emplace_back(c ? c : "");
    }
    return choices;
  }

  // The choices of a radio or menu setting; empty when the camera lacks it.
  std::vector<std::string> ChoicesOf(const std::string& name) {
    auto widget = GetSetting(name);
    return widget.ok() ? Choices(widget->get()) : std::vector<std::string>{};
  }

  Status WriteSetting(const std::string& name, const std::string& value) {
    HR_ASSIGN_OR_RETURN(WidgetPtr widget, GetSetting(name));
    int read_only = 0;
    gp_widget_get_readonly(widget.get(), &read_only);
    if (read_only) return InvalidArgument("setting " + name + " is read-only on this camera");
    const std::vector<std::string> choices = Choices(widget.get());
    if (!choices.empty() && std::find(choices.begin(), choices.end(), value) == choices.end()) {
      std::string list;
      for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
      return OutOfRange("setting " + name + ": '" + value +
                        "' is not one of the camera's choices (" + list + ")");
    }
    gp_widget_set_value(widget.get(), value.c_str());
    return Check(gp_camera_set_single_config(camera_, name.c_str(), widget.get(), context_.get()),
                 "writing setting " + name + " = " + value);
  }

  // The body's serial number, from the settings real bodies report it in.
  Result<std::string> Serial() {
    for (const char* name : {"serialnumber", "eosserialnumber"}) {
      auto serial = ReadText(name);
      if (serial.ok() && !serial->empty()) return serial;
      if (!serial.ok() && serial.status().code() != StatusCode::kNotFound) return serial.status();
    }
    return NotFound("the camera reports no serial number (setting serialnumber)");
  }

  ::Camera* camera() const { return camera_; }  // libgphoto2's handle, not the device interface
  GPContext* context() const { return context_.get(); }
  const std::string& model() const { return model_; }
  const std::string& port() const { return port_; }

 private:
  Gphoto2Session() = default;
  ::Camera* camera_ = nullptr;
  Gphoto2Context context_;
  std::string model_;
  std::string port_;
  int last_result_ = GP_OK;
};

Result<std::vector<std::pair<std::string, std::string>>> AutoDetect() {
  HR_ASSIGN_OR_RETURN(Gphoto2Catalog * catalog, Gphoto2Catalog::Get());
  Gphoto2Context context;
  ListPtr list = NewList();
  const int r =
      gp_abilities_list_detect(catalog->abilities, catalog->ports, list.get(), context.get());
  if (r < GP_OK) return Gphoto2Status(r, "libgphoto2 auto-detection", context.TakeError());
  std::vector<std::pair<std::string, std::string>> found;
  for (int i = 0; i < gp_list_count(list.get()); ++i) {
    const char* model = nullptr;
    const char* port = nullptr;
    gp_list_get_name(list.get(), i, &model);
    gp_list_get_value(list.get(), i, &port);
    found.emplace_back(model ? model : "", port ? port : "");
  }
  return found;
}

double ShutterSeconds(const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  const double first = std::strtod(s, &end);
  if (end == s) return NAN;
  if (*end == '/') return first / std::strtod(end + 1, nullptr);
  return first;
}

// The choice whose value (parsed by `parse`) is nearest `target` in log scale.
std::string NearestChoice(const std::vector<std::string>& choices, double target,
                          double (*parse)(const std::string&)) {
  std::string best;
  double best_error = INFINITY;
  for (const std::string& c : choices) {
    const double v = parse(c);
    if (!(v > 0)) continue;
    const double error = std::abs(std::log(v / target));
    if (error < best_error) {
      best_error = error;
      best = c;
    }
  }
  return best;
}

double IsoValue(const std::string& text) { return std::strtod(text.c_str(), nullptr); }

// --- the device ----------------------------------------------------------------

class Gphoto2Camera : public Camera {
 public:
  Gphoto2Camera(DeviceInfo info, Gphoto2CameraOptions options)
      : Camera(std::move(info)), options_(std::move(options)) {}
  ~Gphoto2Camera() override { (void)Gphoto2Camera::DoClose(); }

  double time_scale() const override { return options_.nominal.time_scale; }

  CameraCapabilities capabilities() const override {
    return {.width_px = options_.nominal.width_px,
            .height_px = options_.nominal.height_px,
            .formats = {PixelFormat::kEncoded},
            .min_exposure_s = min_exposure_s_,
            .max_exposure_s = max_exposure_s_,
            .line_trigger = true,
            .readout_s = options_.nominal.readout_s,
            .download_s = options_.nominal.download_s};
  }

 protected:
  Status DoOpen() override {
    std::lock_guard<std::mutex> lock(mutex_);
    session_.reset();
    HR_ASSIGN_OR_RETURN(session_, FindBySerial());
    for (const auto& [name, value] : options_.settings) {
      Status s = session_->WriteSetting(name, value);
      if (!s.ok()) {
        session_.reset();
        return Fault(InvalidArgument("settings." + name + ": " + s.message()));
      }
    }
    // Read once per Open: Configure picks from them for every capture.
    shutter_choices_ = session_->ChoicesOf("shutterspeed");
    iso_choices_ = session_->ChoicesOf("iso");
    ReadExposureRange();
    SetState(DeviceState::kReady);
    return Status::Ok();
  }

  Status DoClose() override {
    std::lock_guard<std::mutex> lock(mutex_);
    session_.reset();
    return Status::Ok();
  }

  Status DoHealthCheck() override {
    std::lock_guard<std::mutex> lock(mutex_);
    auto serial = session_->Serial();
    if (!serial.ok()) return FaultIfGone(serial.status());
    return Status::Ok();
  }

  Status DoConfigure(const CaptureSettings& s) override {
    HR_RETURN_IF_ERROR(CheckExposure(*this, capabilities(), s.exposure_s));
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string shutter = NearestChoice(shutter_choices_, s.exposure_s, ShutterSeconds);
    if (!shutter.empty()) HR_RETURN_IF_ERROR(WriteSettingRetrying("shutterspeed", shutter));
    const std::string iso =
        NearestChoice(iso_choices_, 100.0 * std::pow(10.0, s.gain_db / 20.0), IsoValue);
    if (!iso.empty()) HR_RETURN_IF_ERROR(WriteSettingRetrying("iso", iso));
    settings_ = s;
    exposure_s_ = shutter.empty() ? s.exposure_s : ShutterSeconds(shutter);
    return Status::Ok();
  }

  Status DoArm() override {
    std::lock_guard<std::mutex> lock(mutex_);
    sequence_ = 0;
    triggers_.Clear();
    return DiscardQueuedFilesLocked();
  }

  // Arming starts nothing on the body that disarming would stop.
  Status DoDisarm() override { return Status::Ok(); }

  Status DoSoftwareTrigger() override {
    std::lock_guard<std::mutex> lock(mutex_);
    const int64_t t = SteadyNowNs();
    HR_RETURN_IF_ERROR(FaultIfGone(Retrying("trigger", [this] {
      return session_->Check(gp_camera_trigger_capture(session_->camera(), session_->context()),
                             "trigger_capture");
    })));
    triggers_.Sent(t);
    return Status::Ok();
  }

  void DoLineTriggerSent(int64_t sent_ns) override { triggers_.Sent(sent_ns); }

  // The body's live view (gp_camera_capture_preview): no shutter, no file.
  Result<Frame> DoCapturePreview(std::chrono::milliseconds timeout) override {
    (void)timeout;  // libgphoto2 bounds the call itself
    std::lock_guard<std::mutex> lock(mutex_);
    CameraFile* raw_file = nullptr;
    gp_file_new(&raw_file);
    std::unique_ptr<CameraFile, FileDeleter> file(raw_file);
    const int r = gp_camera_capture_preview(session_->camera(), file.get(), session_->context());
    if (r == GP_ERROR_NOT_SUPPORTED)
      return Unimplemented(Describe() + ": the body offers no live view through libgphoto2");
    HR_RETURN_IF_ERROR(FaultIfGone(session_->Check(r, Describe() + ": live view")));
    const char* bytes = nullptr;
    unsigned long size = 0;
    gp_file_get_data_and_size(file.get(), &bytes, &size);
    Frame f;
    f.camera_serial = info().serial;
    f.format = PixelFormat::kEncoded;
    f.encoding = "jpg";
    f.data.assign(bytes, bytes + size);
    f.exposure_s = exposure_s_;
    f.gain_db = settings_.gain_db;
    f.received_time_ns = SteadyNowNs();
    f.trigger_time_ns = f.received_time_ns;
    return f;  // width and height stay 0: the preview's size is the body's, read on decoding
  }

  Result<Frame> DoWaitFrame(std::chrono::milliseconds timeout) override {
    const auto deadline = Clock::now() + timeout;
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      if (left.count() <= 0) {
        return Timeout(Describe() + ": no new file from the camera within " +
                       std::to_string(timeout.count()) + " ms");
      }
      // Short waits, so that a trigger from another thread gets the camera in between.
      const int slice_ms = static_cast<int>(std::min<int64_t>(left.count(), 50));
      std::lock_guard<std::mutex> lock(mutex_);
      CameraEventType type = GP_EVENT_UNKNOWN;
      void* data = nullptr;
      const int r =
          gp_camera_wait_for_event(session_->camera(), slice_ms, &type, &data, session_->context());
      if (r < GP_OK) return FaultIfGone(session_->Check(r, Describe() + ": waiting for the shot"));
      if (type != GP_EVENT_FILE_ADDED) {
        free(data);
        continue;
      }
      const CameraFilePath path = *static_cast<CameraFilePath*>(data);
      free(data);
      return DownloadLocked(path);
    }
  }

 private:
  // Opens the configured port, or every auto-detected camera in turn, until
  // one reports the configured serial.
  Result<std::unique_ptr<Gphoto2Session>> FindBySerial() {
    std::vector<std::pair<std::string, std::string>> candidates;
    if (!options_.port.empty() && !options_.model.empty()) {
      candidates.emplace_back(options_.model, options_.port);
    } else {
      auto detected = AutoDetect();
      if (!detected.ok()) return Fault(detected.status());
      for (const auto& c : *detected) {
        if (!options_.port.empty() && c.second != options_.port) continue;
        if (!options_.model.empty() && c.first != options_.model) continue;
        candidates.push_back(c);
      }
    }
    std::string seen;
    Status first_error = Status::Ok();
    for (const auto& [model, port] : candidates) {
      auto session = Gphoto2Session::Open(model, port);
      if (!session.ok()) {
        if (first_error.ok()) first_error = session.status();
        seen += (seen.empty() ? "" : "; ") + session.status().message();
        continue;
      }
      auto serial = (*session)->Serial();
      if (serial.ok() && *serial == info().serial) return std::move(session).value();
      seen += (seen.empty() ? "" : "; ") + model + " at " + port + " has serial " +
              (serial.ok() ? "'" + *serial + "'" : serial.status().message());
    }
    // A camera claimed by another process is the likely culprit; say so first.
    if (!first_error.ok() && first_error.code() == StatusCode::kUnavailable &&
        candidates.size() == 1) {
      return Fault(first_error);
    }
    return Fault(Unavailable(
        "not found" + std::string(seen.empty() ? " (libgphoto2 detects no camera)" : ": " + seen) +
        "; check that it is connected, switched on and not in use by another program"));
  }

  void ReadExposureRange() {
    min_exposure_s_ = 1.0 / 8000;
    max_exposure_s_ = 30;
    double lo = INFINITY, hi = 0;
    for (const std::string& c : shutter_choices_) {
      const double v = ShutterSeconds(c);
      if (v > 0) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    }
    if (hi > 0) {
      // Exposures between two choices are rounded to the nearer one.
      min_exposure_s_ = lo / std::sqrt(2.0);
      max_exposure_s_ = hi * std::sqrt(2.0);
    }
  }

  // Retries a call the camera answered busy, as a user retries after the body finishes focusing.
  // `call` returns the Status of one session request; busy is told by the session's last libgphoto2
  // result.
  template <typename Call>
  Status Retrying(const std::string& what, Call call) {
    Status s;
    for (int attempt = 1;; ++attempt) {
      s = call();
      if (s.ok() || session_->last_result() != GP_ERROR_CAMERA_BUSY) break;
      if (attempt >= options_.busy_attempts) {
        return DeviceFault(Describe() + ": " + what + ": " + s.message() + " (" +
                           std::to_string(options_.busy_attempts) + " attempts)");
      }
      std::this_thread::sleep_for(
          std::chrono::duration<double>(options_.busy_backoff_s * options_.nominal.time_scale));
    }
    return s.ok() ? s : Status(s.code(), Describe() + ": " + what + ": " + s.message());
  }

  Status WriteSettingRetrying(const std::string& name, const std::string& value) {
    return FaultIfGone(
        Retrying("setting " + name, [&] { return session_->WriteSetting(name, value); }));
  }

  // Files the body reported before this arming answer no trigger of it (a
  // shot that finished after its view timed out, before a reopen): they would
  // otherwise be paired with the first new trigger. They stay on the card.
  Status DiscardQueuedFilesLocked() {
    constexpr int kMaxQueuedEvents = 1000;
    for (int i = 0; i < kMaxQueuedEvents; ++i) {
      CameraEventType type = GP_EVENT_UNKNOWN;
      void* data = nullptr;
      const int r =
          gp_camera_wait_for_event(session_->camera(), 0, &type, &data, session_->context());
      if (r < GP_OK)
        return FaultIfGone(session_->Check(r, Describe() + ": reading the body's queued events"));
      if (type == GP_EVENT_FILE_ADDED) {
        const auto* path = static_cast<CameraFilePath*>(data);
        LogWarning(Describe() + ": " + path->folder + "/" + path->name +
                   " was reported before the camera was armed; it answers no trigger of this run "
                   "and stays on the card");
      }
      free(data);
      if (type == GP_EVENT_TIMEOUT) return Status::Ok();
    }
    return DeviceFault(Describe() + ": the body reports events without end; power-cycle it");
  }

  // A camera that went away is faulted (Open() reconnects); other errors leave it usable.
  Status FaultIfGone(const Status& s) {
    if (s.ok() || s.code() != StatusCode::kUnavailable) return s;
    session_.reset();
    SetState(DeviceState::kFaulted);
    return s;
  }

  Result<Frame> DownloadLocked(const CameraFilePath& path) {
    CameraFile* raw_file = nullptr;
    gp_file_new(&raw_file);
    std::unique_ptr<CameraFile, FileDeleter> file(raw_file);
    const std::string where = std::string(path.folder) + "/" + path.name;
    HR_RETURN_IF_ERROR(FaultIfGone(Retrying("downloading " + where, [&] {
      return session_->Check(
          gp_camera_file_get(session_->camera(), path.folder, path.name, GP_FILE_TYPE_NORMAL,
                             file.get(), session_->context()),
          "get_file");
    })));
    const char* bytes = nullptr;
    unsigned long size = 0;
    gp_file_get_data_and_size(file.get(), &bytes, &size);
    Frame f;
    f.camera_serial = info().serial;
    f.sequence = sequence_++;
    f.format = PixelFormat::kEncoded;
    f.encoding = Extension(path.name);
    f.data.assign(bytes, bytes + size);
    f.exposure_s = exposure_s_;
    f.gain_db = settings_.gain_db;
    f.received_time_ns = SteadyNowNs();
    f.width_px = options_.nominal.width_px;
    f.height_px = options_.nominal.height_px;
    f.trigger_time_ns =
        triggers_.ForFrame(f.received_time_ns, options_.nominal.LatencyWallS(exposure_s_));
    if (!options_.keep_on_camera) {
      // The shot is safe on the host; a body that already dropped it (RAM target) answers not
      // found.
      const int r =
          gp_camera_file_delete(session_->camera(), path.folder, path.name, session_->context());
      if (r < GP_OK && r != GP_ERROR_FILE_NOT_FOUND) {
        LogWarning(session_
                       ->Check(r, Describe() + ": deleting " + where +
                                      " after download (the card fills up)")
                       .message());
      }
    }
    return f;
  }

  static std::string Extension(const std::string& name) {
    const size_t dot = name.rfind('.');
    std::string ext = dot == std::string::npos ? "jpg" : name.substr(dot + 1);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    return ext == "jpeg" ? "jpg" : ext;
  }

  Gphoto2CameraOptions options_;
  std::mutex mutex_;  // libgphoto2 calls on one camera are not thread-safe
  std::unique_ptr<Gphoto2Session> session_;
  CaptureSettings settings_;
  double exposure_s_ = 0;
  double min_exposure_s_ = 1.0 / 8000;
  double max_exposure_s_ = 30;
  std::vector<std::string> shutter_choices_;  // of the open body
  std::vector<std::string> iso_choices_;
  uint64_t sequence_ = 0;
  TriggerTimes triggers_;
};

}  // namespace

Result<Gphoto2CameraOptions> ParseGphoto2CameraOptions(const ConfigNode& device) {
  device.AllowOnlyKeys({"name", "backend", "serial", "port", "model", "settings", "keep_on_camera",
                        "width_px", "height_px", "readout_s", "download_s", "trigger_line"});
  Gphoto2CameraOptions o;
  o.port = device.String("port", "");
  o.model = device.String("model", "");
  const ConfigNode settings = device.OptionalChild("settings");
  for (const std::string& key : settings.Keys()) o.settings.emplace_back(key, settings.String(key));
  o.keep_on_camera = device.Bool("keep_on_camera", false);
  o.nominal = ReadCameraNominal(device, o.nominal);
  if (o.port.rfind("disk:", 0) == 0 && o.model.empty()) {
    device.Fail("model",
                "a camera on a disk: port needs its model (libgphoto2 cannot detect it there)");
  }
  if (!device.ok()) return device.status();
  return o;
}

Status Gphoto2CameraOptions::Check() const {
  HR_RETURN_IF_ERROR(nominal.Check());
  if (port.rfind("disk:", 0) == 0 && model.empty()) {
    return InvalidArgument(
        "model: a camera on a disk: port needs its model (libgphoto2 cannot detect it there)");
  }
  for (const auto& setting : settings) {
    if (setting.first.empty()) return InvalidArgument("settings: a setting has no name");
  }
  if (busy_attempts < 1) {
    return InvalidArgument("busy_attempts must be at least 1, got " +
                           std::to_string(busy_attempts));
  }
  if (!(busy_backoff_s >= 0) || !std::isfinite(busy_backoff_s))
    return InvalidArgument("busy_backoff_s must be a finite number of seconds, 0 or more");
  return Status::Ok();
}

std::unique_ptr<hairrig::Camera> MakeGphoto2Camera(const DeviceInfo& info,
                                                   Gphoto2CameraOptions options) {
  return std::make_unique<Gphoto2Camera>(info, std::move(options));
}

Result<std::vector<Gphoto2Detected>> DetectGphoto2Cameras() {
  HR_ASSIGN_OR_RETURN(auto found, AutoDetect());
  std::vector<Gphoto2Detected> out;
  for (const auto& [model, port] : found) {
    Gphoto2Detected d{model, port, "", ""};
    auto session = Gphoto2Session::Open(model, port);
    if (!session.ok()) {
      d.error = session.status().message();
    } else {
      auto serial = (*session)->Serial();
      if (serial.ok())
        d.serial = *serial;
      else
        d.error = serial.status().message();
    }
    out.push_back(std::move(d));
  }
  return out;
}

void RegisterGphoto2Backend(DeviceRegistry* registry, Gphoto2OptionsHook hook) {
  registry->AddBackend<hairrig::Camera>(
      DeviceKind::kCamera, "gphoto2",
      [hook](const DeviceConfig& c) -> Result<std::unique_ptr<hairrig::Camera>> {
        HR_ASSIGN_OR_RETURN(Gphoto2CameraOptions options, ParseGphoto2CameraOptions(c.node));
        if (hook) HR_RETURN_IF_ERROR(hook(c, &options));
        HR_RETURN_IF_ERROR(options.Check().WithContext("camera " + c.name));
        const std::string where = options.port.empty() ? "found by serial" : options.port;
        return MakeGphoto2Camera(
            c.Info("libgphoto2 camera" + (options.model.empty() ? "" : " " + options.model) + " (" +
                   where + ")"),
            std::move(options));
      });
}

}  // namespace hairrig
