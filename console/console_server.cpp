#include "console/console_server.h"

#include <arpa/inet.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <nlohmann/json.hpp>
#include <thread>

#include "console/control_lease.h"
#include "console/event_hub.h"
#include "console/http_server.h"
#include "console/web_assets.h"
#include "core/file_util.h"
#include "core/json_file.h"
#include "core/log.h"
#include "core/string_format.h"

namespace hairrig {

namespace {

using Request = HttpRequest;
using Response = HttpResponse;

constexpr const char* kLeaseHeader = "X-Hairrig-Lease";

// host:port, with [v6]:port.
Status SplitListen(const std::string& listen, std::string* host, int* port) {
  const size_t colon = listen.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == listen.size())
    return InvalidArgument("listen: expected host:port, got '" + listen + "'");
  *host = listen.substr(0, colon);
  if (host->front() == '[' && host->back() == ']') *host = host->substr(1, host->size() - 2);
  const std::string port_text = listen.substr(colon + 1);
  if (port_text.find_first_not_of("0123456789") != std::string::npos || port_text.size() > 5)
    return InvalidArgument("listen: port '" + port_text + "' is not a number in [0, 65535]");
  *port = std::stoi(port_text);
  if (*port > 65535) return InvalidArgument("listen: port " + port_text + " is above 65535");
  return Status::Ok();
}

int HttpStatusOf(const Status& s) {
  switch (s.code()) {
    case StatusCode::kInvalidArgument:
    case StatusCode::kOutOfRange:
    case StatusCode::kCorruptData:
      return 400;
    case StatusCode::kNotFound:
      return 404;
    case StatusCode::kFailedPrecondition:
      return 409;
    case StatusCode::kUnavailable:
    case StatusCode::kTimeout:
      return 503;
    default:
      return 500;
  }
}

// JSON text that never throws: bytes that are not UTF-8 (a name read from a
// capture's files) become U+FFFD.
std::string JsonText(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void SendJson(Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.SetHeader("Cache-Control", "no-store");
  res.SetContent(JsonText(body), "application/json");
}

void SendError(Response& res, const Status& s) {
  SendJson(res, HttpStatusOf(s), {{"error", s.message()}});
}

void SendResult(Response& res, const Result<nlohmann::json>& result, int ok_status = 200) {
  if (result.ok())
    SendJson(res, ok_status, *result);
  else
    SendError(res, result.status());
}

// The request's JSON object ("{}" when the body is empty). InvalidArgument
// naming what is wrong.
Result<nlohmann::json> BodyObject(const Request& req) {
  if (req.body.empty()) return nlohmann::json::object();
  if (req.body.size() > 64 * 1024) return InvalidArgument("request body: larger than 64 KiB");
  HR_ASSIGN_OR_RETURN(nlohmann::json body, ParseJson(req.body, "request body"));
  if (!body.is_object()) return InvalidArgument("request body: expected a JSON object");
  return body;
}

std::string HostOfHeader(const std::string& host_header) {
  if (!host_header.empty() && host_header.front() == '[') {
    const size_t end = host_header.find(']');
    return end == std::string::npos ? host_header : host_header.substr(1, end - 1);
  }
  return host_header.substr(0, host_header.find(':'));
}

// The server's options with room for the event streams and the page's own requests.
HttpServerOptions HttpOptions(const ConsoleOptions& options) {
  HttpServerOptions http = options.http;
  http.max_streams = std::max(http.max_streams, options.max_event_streams);
  return http;
}

std::string SseMessage(const ConsoleEvent& e) {
  return "id: " + std::to_string(e.seq) + "\nevent: " + e.name + "\ndata: " + JsonText(e.data) +
         "\n\n";
}

const EmbeddedFile* FindAsset(const std::vector<EmbeddedFile>& assets, const std::string& path) {
  for (const EmbeddedFile& f : assets) {
    if (path == f.path) return &f;
  }
  return nullptr;
}

std::string AssetContentType(const std::string& path) {
  if (path.ends_with(".html")) return "text/html; charset=utf-8";
  if (path.ends_with(".js")) return "text/javascript; charset=utf-8";
  if (path.ends_with(".css")) return "text/css; charset=utf-8";
  return "application/octet-stream";
}

}  // namespace

bool IsLoopbackHost(const std::string& host) {
  if (host == "localhost" || host == "::1") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  return false;
}

Status ConsoleOptions::Check() const {
  HR_RETURN_IF_ERROR(rig.Check().WithContext("rig"));
  std::string host;
  int port = 0;
  HR_RETURN_IF_ERROR(SplitListen(listen, &host, &port));
  if (!IsLoopbackHost(host) && token.empty())
    return InvalidArgument("listen: " + host +
                           " is beyond loopback: a token is required (--token, or the "
                           "HAIRRIG_CONSOLE_TOKEN environment variable)");
  if (!token.empty() && token.size() < 16) return InvalidArgument("token: at least 16 characters");
  if (lease_ttl.count() <= 0) return InvalidArgument("lease_ttl must be positive");
  if (max_event_streams < 1) return InvalidArgument("max_event_streams must be at least 1");
  return http.Check();
}

class ConsoleServer::Impl {
 public:
  explicit Impl(ConsoleOptions options)
      : options_(std::move(options)),
        rig_(options_.rig, events_),
        lease_(options_.lease_ttl),
        http_(HttpOptions(options_)) {}

  // Parses options.listen into *host and *port (the port bound when 0 was asked).
  Status Start(std::string* host, int* port);
  void Stop();

 private:
  // True when it has answered (refused) the request itself.
  bool Screen(const Request& req, Response& res) const;
  bool HoldsControl(const Request& req, Response& res);
  std::string WhoAsks(const Request& req, const nlohmann::json& body) const;
  nlohmann::json StateWithControl();
  nlohmann::json ControlJson() const;  // {"holder": name or null}
  void Routes();
  void StaticRoutes();
  void RigRoutes();
  void CaptureRoutes();
  void ArchiveRoutes();
  void ControlRoutes();
  void EventRoutes();
  // Registers a POST that needs the control lease; `act` gets the body.
  void ControlledPost(const std::string& pattern,
                      std::function<void(const Request&, Response&, const nlohmann::json&)> act);

  ConsoleOptions options_;
  EventHub events_;
  ConsoleRig rig_;
  ControlLease lease_;
  HttpServer http_;
  std::atomic<int> streams_{0};
  bool loopback_ = true;
  bool started_ = false;
};

bool ConsoleServer::Impl::Screen(const Request& req, Response& res) const {
  if (loopback_ && !IsLoopbackHost(HostOfHeader(req.Header("Host")))) {
    SendJson(res, 403, {{"error", "this console answers only to a loopback Host"}});
    return true;
  }
  if (!options_.token.empty() && req.path.starts_with("/api/")) {
    std::string given = req.Param("token");
    const std::string auth = req.Header("Authorization");
    if (auth.starts_with("Bearer ")) given = auth.substr(7);
    if (!SecretsEqual(given, options_.token)) {
      SendJson(res, 401, {{"error", "a valid token is required (Authorization: Bearer ...)"}});
      return true;
    }
  }
  if ((req.method == "POST" || req.method == "DELETE") &&
      !req.Header("Content-Type").starts_with("application/json")) {
    SendJson(res, 415, {{"error", "send the request with Content-Type: application/json"}});
    return true;
  }
  return false;
}

bool ConsoleServer::Impl::HoldsControl(const Request& req, Response& res) {
  if (lease_.Check(req.Header(kLeaseHeader))) return true;
  const std::optional<std::string> holder = lease_.Holder();
  SendJson(res, 403,
           {{"error", holder ? "read-only: " + *holder + " holds control"
                             : "read-only: claim control first (POST /api/control)"},
            {"holder", holder ? nlohmann::json(*holder) : nlohmann::json(nullptr)}});
  return false;
}

std::string ConsoleServer::Impl::WhoAsks(const Request& req, const nlohmann::json& body) const {
  if (body.contains("client") && body["client"].is_string()) {
    const std::string client = body["client"].get<std::string>();
    if (!client.empty() && client.size() <= 64) return client;
  }
  return "a client at " + req.remote_addr;
}

nlohmann::json ConsoleServer::Impl::ControlJson() const {
  const std::optional<std::string> holder = lease_.Holder();
  return {{"holder", holder ? nlohmann::json(*holder) : nlohmann::json(nullptr)}};
}

nlohmann::json ConsoleServer::Impl::StateWithControl() {
  nlohmann::json state = rig_.State();
  state["control"] = ControlJson();
  return state;
}

void ConsoleServer::Impl::ControlledPost(
    const std::string& pattern,
    std::function<void(const Request&, Response&, const nlohmann::json&)> act) {
  http_.Route("POST", pattern, [this, act](const Request& req, Response& res) {
    Result<nlohmann::json> body = BodyObject(req);
    if (!body.ok()) return SendError(res, body.status());
    if (!HoldsControl(req, res)) return;
    act(req, res, *body);
  });
}

void ConsoleServer::Impl::StaticRoutes() {
  auto serve = [](const std::vector<EmbeddedFile>& assets, const std::string& path, Response& res) {
    const EmbeddedFile* f = FindAsset(assets, path);
    if (!f) return SendJson(res, 404, {{"error", "no such page"}});
    res.SetHeader("Cache-Control", "no-cache");
    res.SetContent(reinterpret_cast<const char*>(f->data), f->size, AssetContentType(path));
  };
  http_.Route("GET", "/", [serve](const Request&, Response& res) {
    serve(ConsoleWebAssets(), "index.html", res);
  });
  http_.Route("GET", R"(/([a-z]+\.(html|js|css)))", [serve](const Request& req, Response& res) {
    serve(ConsoleWebAssets(), req.matches[1], res);
  });
  // Looked up by exact name among the embedded files (nothing is read from disk).
  http_.Route("GET", R"(/vendor/(three/[A-Za-z/.]{1,120}))",
              [serve](const Request& req, Response& res) {
                serve(ConsoleVendorAssets(), req.matches[1], res);
              });
}

void ConsoleServer::Impl::RigRoutes() {
  http_.Route("GET", "/api/state",
              [this](const Request&, Response& res) { SendJson(res, 200, StateWithControl()); });
  http_.Route("GET", "/api/devices",
              [this](const Request&, Response& res) { SendJson(res, 200, rig_.Devices()); });
  ControlledPost(R"(/api/devices/([^/]+)/reconnect)",
                 [this](const Request& req, Response& res, const nlohmann::json&) {
                   SendResult(res, rig_.Reconnect(req.matches[1]));
                 });
  http_.Route("GET", "/api/cameras",
              [this](const Request&, Response& res) { SendJson(res, 200, rig_.Cameras()); });
  http_.Route(
      "GET", R"(/api/cameras/([^/]+)/preview\.jpg)", [this](const Request& req, Response& res) {
        const std::string name = req.matches[1];
        if (!rig_.HasCamera(name))
          return SendJson(res, 404, {{"error", "no camera named '" + name.substr(0, 64) + "'"}});
        const std::optional<LivePreview> preview = rig_.Preview(name);
        if (!preview) return SendJson(res, 404, {{"error", "no frame from " + name + " yet"}});
        res.SetHeader("Cache-Control", "no-store");
        res.SetHeader("X-Hairrig-Seq", std::to_string(preview->seq));
        res.SetContent(reinterpret_cast<const char*>(preview->jpeg.data()), preview->jpeg.size(),
                       "image/jpeg");
      });
  ControlledPost(R"(/api/cameras/([^/]+)/settings)",
                 [this](const Request& req, Response& res, const nlohmann::json& body) {
                   const JsonObject b(body, "request body");
                   std::optional<double> exposure, gain;
                   if (b.Has("exposure_s")) exposure = b.Number("exposure_s");
                   if (b.Has("gain_db")) gain = b.Number("gain_db");
                   if (!b.ok()) return SendError(res, b.status());
                   SendResult(res, rig_.SetCameraExposure(req.matches[1], exposure, gain));
                 });
  ControlledPost("/api/lights", [this](const Request&, Response& res, const nlohmann::json& body) {
    const JsonObject b(body, "request body");
    std::map<std::string, bool> on;
    for (const std::string& key : b.Keys()) {
      if (key != "client") on[key] = b.Bool(key);
    }
    if (!b.ok()) return SendError(res, b.status());
    SendResult(res, rig_.SetLights(on));
  });
  ControlledPost("/api/turntable/jog",
                 [this](const Request&, Response& res, const nlohmann::json& body) {
                   const JsonObject b(body, "request body");
                   const double degrees = b.Number("degrees", {.min = -360, .max = 360});
                   if (!b.ok()) return SendError(res, b.status());
                   SendResult(res, rig_.Jog(degrees));
                   events_.Publish("state", rig_.State());
                 });
  ControlledPost("/api/turntable/home",
                 [this](const Request&, Response& res, const nlohmann::json&) {
                   SendResult(res, rig_.Home());
                   events_.Publish("state", rig_.State());
                 });
  http_.Route("GET", "/api/plan",
              [this](const Request&, Response& res) { SendJson(res, 200, rig_.Plan()); });
}

void ConsoleServer::Impl::CaptureRoutes() {
  ControlledPost(
      "/api/captures", [this](const Request&, Response& res, const nlohmann::json& body) {
        const JsonObject b(body, "request body");
        const std::string subject = b.String("subject");
        const bool calibrate = b.BoolOr("calibrate", true);
        const bool reconstruct = b.BoolOr("reconstruct", false);
        if (!b.ok()) return SendError(res, b.status());
        const Result<std::string> id = rig_.StartCapture(subject, calibrate, reconstruct);
        if (!id.ok()) return SendError(res, id.status());
        SendJson(res, 202, {{"id", *id}});
      });
  ControlledPost(R"(/api/captures/([^/]+)/resume)", [this](const Request& req, Response& res,
                                                           const nlohmann::json& body) {
    const JsonObject b(body, "request body");
    const bool calibrate = b.BoolOr("calibrate", true);
    const bool reconstruct = b.BoolOr("reconstruct", false);
    if (!b.ok()) return SendError(res, b.status());
    const Result<std::string> id = rig_.ResumeCapture(req.matches[1], calibrate, reconstruct);
    if (!id.ok()) return SendError(res, id.status());
    SendJson(res, 202, {{"id", *id}});
  });
  ControlledPost(R"(/api/captures/([^/]+)/replay)",
                 [this](const Request& req, Response& res, const nlohmann::json&) {
                   const Result<std::string> id = rig_.ReplayCapture(req.matches[1]);
                   if (!id.ok()) return SendError(res, id.status());
                   SendJson(res, 202, {{"id", *id}});
                 });
  ControlledPost("/api/capture/stop",
                 [this](const Request& req, Response& res, const nlohmann::json&) {
                   const Status s = rig_.StopCapture(lease_.Holder().value_or(req.remote_addr));
                   if (!s.ok()) return SendError(res, s);
                   SendJson(res, 200, {{"stopping", true}});
                 });
  // The e-stop needs no lease: any client may press it. It has a thread of
  // its own in the server, so no other request can delay it.
  http_.Route(
      "POST", "/api/estop",
      [this](const Request& req, Response& res) {
        const Result<nlohmann::json> body = BodyObject(req);
        const nlohmann::json estop =
            rig_.EStop(WhoAsks(req, body.ok() ? *body : nlohmann::json::object()));
        SendJson(res, 200, {{"estop", estop}});
      },
      HttpLane::kUrgent);
  ControlledPost("/api/estop/release",
                 [this](const Request&, Response& res, const nlohmann::json&) {
                   const Status s = rig_.ReleaseEStop();
                   if (!s.ok()) return SendError(res, s);
                   SendJson(res, 200, {{"estop", {{"active", false}}}});
                 });
}

void ConsoleServer::Impl::ArchiveRoutes() {
  http_.Route("GET", "/api/captures", [this](const Request&, Response& res) {
    nlohmann::json list = nlohmann::json::array();
    for (const ArchiveEntry& e : rig_.archive().List()) list.push_back(e.ToJson());
    SendJson(res, 200, {{"captures", list}});
  });
  http_.Route("GET", R"(/api/captures/([^/]+))", [this](const Request& req, Response& res) {
    SendResult(res, rig_.archive().Details(req.matches[1]));
  });
  http_.Route("GET", R"(/api/captures/([^/]+)/views/(\d{1,6})/thumb\.jpg)",
              [this](const Request& req, Response& res) {
                const std::string id = req.matches[1];
                const int view = std::stoi(req.matches[2]);
                std::optional<std::vector<uint8_t>> jpeg = rig_.CachedThumbnail(id, view);
                if (!jpeg) {
                  Result<std::vector<uint8_t>> read = rig_.archive().Thumbnail(id, view, 240);
                  if (!read.ok()) return SendError(res, read.status());
                  jpeg = std::move(*read);
                }
                res.SetHeader("Cache-Control", "max-age=3600");
                res.SetContent(reinterpret_cast<const char*>(jpeg->data()), jpeg->size(),
                               "image/jpeg");
              });
  http_.Route(
      "GET", R"(/api/captures/([^/]+)/files/(.+))", [this](const Request& req, Response& res) {
        const Result<std::string> path = rig_.archive().FilePath(req.matches[1], req.matches[2]);
        if (!path.ok()) return SendError(res, path.status());
        const Result<std::vector<uint8_t>> bytes = ReadFileBytes(*path, uint64_t{256} << 20);
        if (!bytes.ok()) return SendError(res, bytes.status());
        res.SetHeader("Cache-Control", "no-cache");
        res.SetContent(reinterpret_cast<const char*>(bytes->data()), bytes->size(),
                       ContentTypeOf(*path));
      });
}

void ConsoleServer::Impl::ControlRoutes() {
  http_.Route("POST", "/api/control", [this](const Request& req, Response& res) {
    const Result<nlohmann::json> body = BodyObject(req);
    if (!body.ok()) return SendError(res, body.status());
    const JsonObject b(*body, "request body");
    const std::string client = b.String("client");
    const bool take = b.BoolOr("take", false);
    if (!b.ok()) return SendError(res, b.status());
    const Result<ControlLease::Grant> grant = lease_.Claim(client, take);
    if (!grant.ok()) {
      const std::optional<std::string> holder = lease_.Holder();
      return SendJson(res, HttpStatusOf(grant.status()),
                      {{"error", grant.status().message()},
                       {"holder", holder ? nlohmann::json(*holder) : nlohmann::json(nullptr)}});
    }
    SendJson(res, 200,
             {{"lease", grant->lease},
              {"holder", grant->holder},
              {"expires_s", std::chrono::duration<double>(lease_.ttl()).count()}});
    events_.Publish("state", StateWithControl());
  });
  http_.Route("POST", "/api/control/heartbeat", [this](const Request& req, Response& res) {
    if (!HoldsControl(req, res)) return;
    SendJson(res, 200, {{"holder", lease_.Holder().value_or("")}});
  });
  http_.Route("DELETE", "/api/control", [this](const Request& req, Response& res) {
    if (!lease_.Release(req.Header(kLeaseHeader)))
      return SendJson(res, 403, {{"error", "this lease does not hold control"}});
    SendJson(res, 200, {{"released", true}});
    events_.Publish("state", StateWithControl());
  });
}

void ConsoleServer::Impl::EventRoutes() {
  http_.Route("GET", "/api/events", [this](const Request&, Response& res) {
    if (streams_.fetch_add(1) >= options_.max_event_streams) {
      --streams_;
      return SendJson(res, 503, {{"error", "too many event streams open; close one"}});
    }
    res.SetHeader("Cache-Control", "no-store");
    auto state = std::make_shared<std::pair<uint64_t, bool>>(events_.last_seq(), true);
    res.content_type = "text/event-stream";
    res.stream = [this, state](HttpStreamSink& sink) {
      auto& [after, first] = *state;
      if (first) {
        first = false;
        return sink.Write(SseMessage({after, "state", StateWithControl()}) + "retry: 2000\n\n");
      }
      const std::vector<ConsoleEvent> events = events_.WaitAfter(after, std::chrono::seconds(10));
      if (events_.closed()) return false;
      std::string text = events.empty() ? ": keep-alive\n\n" : "";
      for (ConsoleEvent e : events) {
        if (e.name == "state") e.data["control"] = ControlJson();
        text += SseMessage(e);
        after = e.seq;
      }
      return sink.Write(text);
    };
    res.on_stream_end = [this] { --streams_; };
  });
}

void ConsoleServer::Impl::Routes() {
  http_.SetScreen([this](const Request& req, Response& res) { return Screen(req, res); });
  StaticRoutes();
  RigRoutes();
  CaptureRoutes();
  ArchiveRoutes();
  ControlRoutes();
  EventRoutes();
}

Status ConsoleServer::Impl::Start(std::string* host, int* port) {
  HR_RETURN_IF_ERROR(options_.Check());
  HR_RETURN_IF_ERROR(SplitListen(options_.listen, host, port));
  loopback_ = IsLoopbackHost(*host);
  HR_RETURN_IF_ERROR(rig_.Start());
  started_ = true;
  Routes();
  HR_RETURN_IF_ERROR(http_.Listen(*host, *port));
  *port = http_.port();
  return Status::Ok();
}

void ConsoleServer::Impl::Stop() {
  events_.Close();
  http_.Stop();
  if (started_) rig_.Shutdown();
  started_ = false;
}

ConsoleServer::ConsoleServer(ConsoleOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

ConsoleServer::~ConsoleServer() { Stop(); }

Status ConsoleServer::Start() { return impl_->Start(&host_, &port_); }

void ConsoleServer::Stop() {
  if (impl_) impl_->Stop();
}

std::string ConsoleServer::url() const {
  const std::string host = host_.find(':') != std::string::npos ? "[" + host_ + "]" : host_;
  return "http://" + host + ":" + std::to_string(port_) + "/";
}

nlohmann::json ConsoleSummary::ToJson() const { return {{"url", url}, {"served_s", served_s}}; }

std::string ConsoleSummary::BriefReport() const {
  return StringPrintf("console at %s served for %.0f s\n", url.c_str(), served_s);
}

Result<ConsoleSummary> RunConsole(const ConsoleOptions& options, const std::atomic<bool>& stop,
                                  const std::function<void(const std::string& url)>& on_listening) {
  ConsoleServer server(options);
  HR_RETURN_IF_ERROR(server.Start());
  const auto start = std::chrono::steady_clock::now();
  if (on_listening) on_listening(server.url());
  while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  server.Stop();
  ConsoleSummary summary;
  summary.url = server.url();
  summary.served_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace hairrig
