// The wire protocol between the simulated DSLR (sim_hw/sim_dslr_server) and
// the libgphoto2 camera driver that reaches it (sim_hw/gphoto2_camlib).
//
// The camlib runs inside whatever process loaded libgphoto2 (hairrig, the
// `gphoto2` command); the camera it talks to lives in the process that owns
// the simulated world. They meet on a Unix socket, `<folder>/camera.sock`,
// where `<folder>` is the path of the camera's gphoto2 port `disk:<folder>`.
//
// A message is one header line of tab-separated fields: the request id (a
// reply echoes its request's), the verb and its arguments, and last the byte
// count of the payload that follows the newline:
//     7\tCAPTURE\t0\n
//     7\tOK\t/store_00010001/DCIM/100HRSIM\tIMG_0001.JPG\t0\n
//     8\tGET\t/store_00010001/DCIM/100HRSIM\tIMG_0001.JPG\t0\n
//     8\tOK\t812345\n<812345 bytes of JPEG>
// A client that gave up waiting for a reply skips it by id when it comes late.
// Requests: HELLO, CAPTURE, TRIGGER, PREVIEW (a live-view JPEG as the
// payload, no shot), EVENT <timeout_ms>, FOLDERS <folder>,
// FILES <folder>, INFO <folder> <name>, GET <folder> <name>,
// DELETE <folder> <name>, CONFIG, SET <name> <value>, BYE.
// Replies: OK <fields...>, or ERR <kind> <message> with the kinds below.
//
// This header is shared by both ends and depends on nothing in hairrig, so
// the camlib stays a small self-contained module.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace hairrig::sim_dslr {

// The camlib's model name: what `gphoto2 --list-cameras` shows.
inline constexpr const char* kModel = "Hairrig Simulated DSLR";
inline constexpr const char* kSocketName = "camera.sock";
// pid.codes' test id (https://pid.codes/1209/0001/), which the camlib claims
// for USB detection of a simulated body.
inline constexpr int kUsbVendorId = 0x1209;
inline constexpr int kUsbProductId = 0x0001;
inline constexpr const char* kStorageFolder = "/store_00010001";
inline constexpr const char* kImageFolder = "/store_00010001/DCIM/100HRSIM";

// Error kinds of an ERR reply; the camlib maps each to a libgphoto2 result.
inline constexpr const char* kErrBusy = "busy";           // GP_ERROR_CAMERA_BUSY
inline constexpr const char* kErrClaimed = "claimed";     // GP_ERROR_IO_USB_CLAIM
inline constexpr const char* kErrNotFound = "not_found";  // GP_ERROR_FILE_NOT_FOUND
inline constexpr const char* kErrBadValue = "bad_value";  // GP_ERROR_BAD_PARAMETERS
inline constexpr const char* kErrIo = "io";               // GP_ERROR_IO

struct Message {
  uint64_t id = 0;
  std::vector<std::string> fields;  // fields[0] is the verb or OK/ERR
  std::string payload;

  const std::string& field(size_t i) const;  // "" when absent
};

enum class IoResult { kOk, kTimeout, kClosed, kMalformed };

// Writes one message; tabs and newlines inside fields become spaces.
// kClosed when the peer is gone.
IoResult WriteMessage(int fd, uint64_t id, const std::vector<std::string>& fields,
                      const std::string& payload = {});
// Reads one message, waiting at most `timeout_ms` (< 0: no limit) for each
// chunk to arrive. A header over 64 KiB or a payload over 1 GiB is kMalformed.
IoResult ReadMessage(int fd, int timeout_ms, Message* out);

// The socket path for a port path ("disk:/tmp/x" or "/tmp/x"); "" when the
// folder part is empty or the result would not fit a sockaddr_un.
std::string SocketPathForPort(const std::string& port_path);
// Connects to the Unix socket at `path`; -1 with errno set on failure.
int ConnectUnix(const std::string& path);

// One configuration item as the server lists it (a CONFIG reply holds one per
// payload line, fields tab-separated in this order).
struct ConfigItem {
  std::string name;     // "iso", "shutterspeed", ...
  std::string label;    // "ISO Speed"
  std::string section;  // "imgsettings", "capturesettings", "settings", "status"
  bool read_only = false;
  std::string value;
  std::vector<std::string> choices;  // empty for a text item
};
std::string EncodeConfig(const std::vector<ConfigItem>& items);
std::vector<ConfigItem> DecodeConfig(const std::string& payload);

}  // namespace hairrig::sim_dslr
