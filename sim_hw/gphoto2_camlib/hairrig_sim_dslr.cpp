// hairrig_sim_dslr: a libgphoto2 camera driver ("camlib") for the simulated
// DSLR of sim_hw/sim_dslr_server.h.
//
// libgphoto2 loads it like any camlib from the folder named by the CAMLIBS
// environment variable (the build puts it in <build>/camlibs beside links to
// the system's camlibs). Its model, "Hairrig Simulated DSLR", lives on gphoto2
// ports of type disk: the port `disk:<folder>` connects it to the camera
// served on `<folder>/camera.sock`. For example:
//   export CAMLIBS=build/camlibs
//   gphoto2 --camera "Hairrig Simulated DSLR" --port disk:/tmp/hairrig-dslr-XXXX
//           --capture-image-and-download
//
// Supported: capture, trigger capture + wait for FILE_ADDED, get/set config,
// file listing, download and delete, summary. Server errors become the
// libgphoto2 results a real camera gives (busy, claimed, timeout, I/O).
#include <gphoto2/gphoto2-library.h>
#include <gphoto2/gphoto2-port-log.h>
#include <gphoto2/gphoto2-result.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "sim_hw/sim_dslr_protocol.h"

namespace proto = hairrig::sim_dslr;

struct _CameraPrivateLibrary {
  int fd = -1;
  uint64_t next_id = 1;
  int reply_timeout_ms = 30000;
  std::string serial;
};

namespace {

constexpr const char* kLogDomain = "hairrig_sim_dslr";

int ErrorFromKind(const std::string& kind) {
  if (kind == proto::kErrBusy) return GP_ERROR_CAMERA_BUSY;
  if (kind == proto::kErrClaimed) return GP_ERROR_IO_USB_CLAIM;
  if (kind == proto::kErrNotFound) return GP_ERROR_FILE_NOT_FOUND;
  if (kind == proto::kErrBadValue) return GP_ERROR_BAD_PARAMETERS;
  return GP_ERROR_IO;
}

// Sends one request and reads its reply. A reply of ERR is reported through
// the context and returned as the matching libgphoto2 error.
int Call(Camera* camera, GPContext* context, const std::vector<std::string>& request,
         proto::Message* reply) {
  CameraPrivateLibrary* pl = camera->pl;
  if (pl->fd < 0) {
    gp_context_error(context, "The simulated camera connection is closed; reopen the camera.");
    return GP_ERROR_IO;
  }
  const uint64_t id = pl->next_id++;
  if (proto::WriteMessage(pl->fd, id, request) != proto::IoResult::kOk) {
    gp_context_error(context, "The simulated camera went away (%s).", request[0].c_str());
    return GP_ERROR_IO;
  }
  proto::IoResult read = proto::IoResult::kOk;
  // Replies to requests that timed out earlier may still arrive: skip them.
  do {
    read = proto::ReadMessage(pl->fd, pl->reply_timeout_ms, reply);
  } while (read == proto::IoResult::kOk && reply->id < id);
  switch (read) {
    case proto::IoResult::kOk:
      break;
    case proto::IoResult::kTimeout:
      gp_context_error(context, "The simulated camera did not answer %s within %d ms.",
                       request[0].c_str(), pl->reply_timeout_ms);
      return GP_ERROR_TIMEOUT;
    case proto::IoResult::kClosed:
      gp_context_error(context, "The simulated camera went away during %s.", request[0].c_str());
      return GP_ERROR_IO;
    case proto::IoResult::kMalformed:
      gp_context_error(context, "The simulated camera sent a malformed reply to %s.",
                       request[0].c_str());
      return GP_ERROR_CORRUPTED_DATA;
  }
  if (reply->field(0) == "OK") return GP_OK;
  gp_context_error(context, "%s", reply->field(2).c_str());
  return ErrorFromKind(reply->field(1));
}

std::vector<std::string> Lines(const std::string& payload) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < payload.size()) {
    size_t end = payload.find('\n', start);
    if (end == std::string::npos) end = payload.size();
    if (end > start) lines.push_back(payload.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

void CopyText(char* out, size_t size, const std::string& text) {
  std::snprintf(out, size, "%s", text.c_str());
}

// --- filesystem ------------------------------------------------------------

int ListEntries(const char* verb, const char* folder, CameraList* list, void* data,
                GPContext* context) {
  auto* camera = static_cast<Camera*>(data);
  proto::Message reply;
  const int r = Call(camera, context, {verb, folder}, &reply);
  if (r < GP_OK) return r;
  for (const std::string& name : Lines(reply.payload)) gp_list_append(list, name.c_str(), nullptr);
  return GP_OK;
}

int FileList(CameraFilesystem*, const char* folder, CameraList* list, void* data,
             GPContext* context) {
  return ListEntries("FILES", folder, list, data, context);
}

int FolderList(CameraFilesystem*, const char* folder, CameraList* list, void* data,
               GPContext* context) {
  return ListEntries("FOLDERS", folder, list, data, context);
}

int GetInfo(CameraFilesystem*, const char* folder, const char* name, CameraFileInfo* info,
            void* data, GPContext* context) {
  proto::Message reply;
  const int r = Call(static_cast<Camera*>(data), context, {"INFO", folder, name}, &reply);
  if (r < GP_OK) return r;
  std::memset(info, 0, sizeof(*info));
  info->file.fields =
      static_cast<CameraFileInfoFields>(GP_FILE_INFO_SIZE | GP_FILE_INFO_TYPE | GP_FILE_INFO_MTIME);
  info->file.size = std::strtoull(reply.field(1).c_str(), nullptr, 10);
  info->file.mtime = static_cast<time_t>(std::atoll(reply.field(2).c_str()));
  CopyText(info->file.type, sizeof(info->file.type), GP_MIME_JPEG);
  return GP_OK;
}

int GetFile(CameraFilesystem*, const char* folder, const char* name, CameraFileType type,
            CameraFile* file, void* data, GPContext* context) {
  if (type != GP_FILE_TYPE_NORMAL) return GP_ERROR_NOT_SUPPORTED;
  proto::Message reply;
  const int r = Call(static_cast<Camera*>(data), context, {"GET", folder, name}, &reply);
  if (r < GP_OK) return r;
  gp_file_set_mime_type(file, GP_MIME_JPEG);
  return gp_file_append(file, reply.payload.data(),
                        static_cast<unsigned long>(reply.payload.size()));
}

int DeleteFile(CameraFilesystem*, const char* folder, const char* name, void* data,
               GPContext* context) {
  proto::Message reply;
  return Call(static_cast<Camera*>(data), context, {"DELETE", folder, name}, &reply);
}

int StorageInfo(CameraFilesystem*, CameraStorageInformation** infos, int* count, void*,
                GPContext*) {
  auto* info = static_cast<CameraStorageInformation*>(calloc(1, sizeof(CameraStorageInformation)));
  if (info == nullptr) return GP_ERROR_NO_MEMORY;
  info->fields =
      static_cast<CameraStorageInfoFields>(GP_STORAGEINFO_BASE | GP_STORAGEINFO_DESCRIPTION |
                                           GP_STORAGEINFO_ACCESS | GP_STORAGEINFO_STORAGETYPE);
  CopyText(info->basedir, sizeof(info->basedir), proto::kStorageFolder);
  CopyText(info->description, sizeof(info->description), "simulated card");
  info->access = GP_STORAGEINFO_AC_READWRITE;
  info->type = GP_STORAGEINFO_ST_FIXED_RAM;
  *infos = info;
  *count = 1;
  return GP_OK;
}

CameraFilesystemFuncs filesystem_funcs = [] {
  CameraFilesystemFuncs f{};
  f.file_list_func = FileList;
  f.folder_list_func = FolderList;
  f.get_info_func = GetInfo;
  f.get_file_func = GetFile;
  f.del_file_func = DeleteFile;
  f.storage_info_func = StorageInfo;
  return f;
}();

// --- capture ---------------------------------------------------------------

void FillPath(CameraFilePath* path, const std::string& folder, const std::string& name) {
  CopyText(path->folder, sizeof(path->folder), folder);
  CopyText(path->name, sizeof(path->name), name);
}

int Capture(Camera* camera, CameraCaptureType type, CameraFilePath* path, GPContext* context) {
  if (type != GP_CAPTURE_IMAGE) return GP_ERROR_NOT_SUPPORTED;
  proto::Message reply;
  const int r = Call(camera, context, {"CAPTURE"}, &reply);
  if (r < GP_OK) return r;
  FillPath(path, reply.field(1), reply.field(2));
  return gp_filesystem_append(camera->fs, path->folder, path->name, context);
}

int TriggerCapture(Camera* camera, GPContext* context) {
  proto::Message reply;
  return Call(camera, context, {"TRIGGER"}, &reply);
}

// A live-view frame: a small JPEG of what the sensor sees, no shot taken.
int CapturePreview(Camera* camera, CameraFile* file, GPContext* context) {
  proto::Message reply;
  const int r = Call(camera, context, {"PREVIEW"}, &reply);
  if (r < GP_OK) return r;
  gp_file_set_mime_type(file, GP_MIME_JPEG);
  return gp_file_append(file, reply.payload.data(), reply.payload.size());
}

int WaitForEvent(Camera* camera, int timeout_ms, CameraEventType* type, void** data,
                 GPContext* context) {
  *type = GP_EVENT_TIMEOUT;
  *data = nullptr;
  proto::Message reply;
  // The server waits up to timeout_ms; the reply limit covers that too.
  CameraPrivateLibrary* pl = camera->pl;
  const int saved = pl->reply_timeout_ms;
  pl->reply_timeout_ms = saved + std::max(0, timeout_ms);
  const int r = Call(camera, context, {"EVENT", std::to_string(timeout_ms)}, &reply);
  pl->reply_timeout_ms = saved;
  if (r < GP_OK) return r;
  if (reply.field(1) != "FILE_ADDED") return GP_OK;
  auto* path = static_cast<CameraFilePath*>(calloc(1, sizeof(CameraFilePath)));
  if (path == nullptr) return GP_ERROR_NO_MEMORY;
  FillPath(path, reply.field(2), reply.field(3));
  gp_filesystem_append(camera->fs, path->folder, path->name, context);
  *type = GP_EVENT_FILE_ADDED;
  *data = path;
  return GP_OK;
}

// --- configuration -----------------------------------------------------------

int GetConfig(Camera* camera, CameraWidget** window, GPContext* context) {
  proto::Message reply;
  const int r = Call(camera, context, {"CONFIG"}, &reply);
  if (r < GP_OK) return r;
  gp_widget_new(GP_WIDGET_WINDOW, "Camera and Driver Configuration", window);
  gp_widget_set_name(*window, "main");
  for (const proto::ConfigItem& item : proto::DecodeConfig(reply.payload)) {
    CameraWidget* section = nullptr;
    if (gp_widget_get_child_by_name(*window, item.section.c_str(), &section) < GP_OK) {
      gp_widget_new(GP_WIDGET_SECTION, item.section.c_str(), &section);
      gp_widget_set_name(section, item.section.c_str());
      gp_widget_append(*window, section);
    }
    CameraWidget* widget = nullptr;
    gp_widget_new(item.choices.empty() ? GP_WIDGET_TEXT : GP_WIDGET_RADIO, item.label.c_str(),
                  &widget);
    gp_widget_set_name(widget, item.name.c_str());
    for (const std::string& choice : item.choices) gp_widget_add_choice(widget, choice.c_str());
    gp_widget_set_value(widget, item.value.c_str());
    gp_widget_set_readonly(widget, item.read_only ? 1 : 0);
    gp_widget_set_changed(widget, 0);
    gp_widget_append(section, widget);
  }
  return GP_OK;
}

int SetChanged(Camera* camera, CameraWidget* widget, GPContext* context) {
  const int children = gp_widget_count_children(widget);
  for (int i = 0; i < children; ++i) {
    CameraWidget* child = nullptr;
    gp_widget_get_child(widget, i, &child);
    const int r = SetChanged(camera, child, context);
    if (r < GP_OK) return r;
  }
  if (children > 0 || !gp_widget_changed(widget)) return GP_OK;
  const char* name = nullptr;
  const char* value = nullptr;
  gp_widget_get_name(widget, &name);
  gp_widget_get_value(widget, &value);
  proto::Message reply;
  return Call(camera, context, {"SET", name, value ? value : ""}, &reply);
}

int SetConfig(Camera* camera, CameraWidget* window, GPContext* context) {
  return SetChanged(camera, window, context);
}

int Summary(Camera* camera, CameraText* text, GPContext* context) {
  proto::Message reply;
  const int r = Call(camera, context, {"FILES", proto::kImageFolder}, &reply);
  if (r < GP_OK) return r;
  const std::string summary =
      std::string("Model: ") + proto::kModel + "\nSerial Number: " + camera->pl->serial +
      "\nFiles on the camera: " + std::to_string(Lines(reply.payload).size()) + "\n";
  CopyText(text->text, sizeof(text->text), summary);
  return GP_OK;
}

int About(Camera*, CameraText* text, GPContext*) {
  CopyText(text->text, sizeof(text->text),
           "hairrig's simulated DSLR: renders the simulated rig's scene and serves each shot as a "
           "JPEG.\n");
  return GP_OK;
}

int Exit(Camera* camera, GPContext*) {
  if (camera->pl == nullptr) return GP_OK;
  if (camera->pl->fd >= 0) {
    // Waits for BYE's answer (the camera released) so that whoever opens the
    // camera next finds it free; a camera that does not answer is left as is.
    const uint64_t id = camera->pl->next_id++;
    if (proto::WriteMessage(camera->pl->fd, id, {"BYE"}) == proto::IoResult::kOk) {
      proto::Message reply;
      while (proto::ReadMessage(camera->pl->fd, camera->pl->reply_timeout_ms, &reply) ==
                 proto::IoResult::kOk &&
             reply.id < id) {
      }
    }
    close(camera->pl->fd);
  }
  delete camera->pl;
  camera->pl = nullptr;
  return GP_OK;
}

// Connects to the camera behind the port's folder and says HELLO.
int Connect(Camera* camera, GPContext* context) {
  GPPortInfo info;
  char* port_path = nullptr;
  int r = gp_port_get_info(camera->port, &info);
  if (r < GP_OK) return r;
  gp_port_info_get_path(info, &port_path);
  const std::string socket_path = proto::SocketPathForPort(port_path ? port_path : "");
  if (socket_path.empty()) {
    gp_context_error(context,
                     "Port '%s' does not name a simulated camera's folder (use disk:<folder>).",
                     port_path ? port_path : "");
    return GP_ERROR_BAD_PARAMETERS;
  }
  camera->pl->fd = proto::ConnectUnix(socket_path);
  if (camera->pl->fd < 0) {
    gp_context_error(context, "No simulated camera at %s (%s). Is `hairrig sim serve` running?",
                     socket_path.c_str(), std::strerror(errno));
    return GP_ERROR_IO_USB_FIND;
  }
  proto::Message reply;
  r = Call(camera, context, {"HELLO", std::to_string(getpid())}, &reply);
  if (r == GP_ERROR_IO) {
    gp_context_error(context, "The simulated camera at %s is not answering (dropped off the bus?).",
                     socket_path.c_str());
    return GP_ERROR_IO_USB_FIND;
  }
  if (r < GP_OK) return r;
  camera->pl->serial = reply.field(2);
  const int timeout_ms = std::atoi(reply.field(3).c_str());
  if (timeout_ms > 0) camera->pl->reply_timeout_ms = timeout_ms;
  gp_log(GP_LOG_DEBUG, kLogDomain, "connected to %s (serial %s)", socket_path.c_str(),
         camera->pl->serial.c_str());
  return GP_OK;
}

}  // namespace

extern "C" {

int camera_id(CameraText* id) {
  CopyText(id->text, sizeof(id->text), "hairrig-sim-dslr");
  return GP_OK;
}

int camera_abilities(CameraAbilitiesList* list) {
  CameraAbilities a;
  std::memset(&a, 0, sizeof(a));
  CopyText(a.model, sizeof(a.model), proto::kModel);
  CopyText(a.id, sizeof(a.id), "hairrig-sim-dslr");
  a.status = GP_DRIVER_STATUS_TESTING;
  // Its camera lives on a disk: port (the folder of its socket). It also
  // claims the pid.codes test id 1209:0001, so that libgphoto2's USB
  // auto-detection lists it where a USB device with that id is enumerated
  // (the tests give one through umockdev); it is not opened over USB.
  a.port = static_cast<GPPortType>(GP_PORT_DISK | GP_PORT_USB);
  a.usb_vendor = proto::kUsbVendorId;
  a.usb_product = proto::kUsbProductId;
  a.operations = static_cast<CameraOperation>(GP_OPERATION_CAPTURE_IMAGE |
                                              GP_OPERATION_TRIGGER_CAPTURE | GP_OPERATION_CONFIG);
  a.file_operations = GP_FILE_OPERATION_DELETE;
  a.folder_operations = GP_FOLDER_OPERATION_NONE;
  a.device_type = GP_DEVICE_STILL_CAMERA;
  return gp_abilities_list_append(list, a);
}

int camera_init(Camera* camera, GPContext* context) {
  camera->pl = new (std::nothrow) CameraPrivateLibrary();
  if (camera->pl == nullptr) return GP_ERROR_NO_MEMORY;
  camera->functions->exit = Exit;
  camera->functions->capture = Capture;
  camera->functions->trigger_capture = TriggerCapture;
  camera->functions->capture_preview = CapturePreview;
  camera->functions->wait_for_event = WaitForEvent;
  camera->functions->get_config = GetConfig;
  camera->functions->set_config = SetConfig;
  camera->functions->summary = Summary;
  camera->functions->about = About;
  gp_filesystem_set_funcs(camera->fs, &filesystem_funcs, camera);
  const int r = Connect(camera, context);
  if (r < GP_OK) Exit(camera, context);
  return r;
}

}  // extern "C"
