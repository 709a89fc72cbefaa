// The console's HTTP server on its own: routing, keep-alive, the request
// limits, and that no load of connections or busy workers delays an urgent route.
#include "console/http_server.h"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "tests/support/open_file_limit.h"
#include "tests/support/raw_http.h"

namespace hairrig {
namespace {

using namespace std::chrono_literals;
using hairrig_test::ConnectLoopback;
using hairrig_test::PeerClosed;
using hairrig_test::RawRequest;
using hairrig_test::SendText;

// Reads whatever arrives on `fd` within `timeout` (until the peer closes).
std::string ReadFor(int fd, std::chrono::milliseconds timeout) {
  std::string text;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  char buffer[4096];
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
    if (n <= 0) break;
    text.append(buffer, static_cast<size_t>(n));
  }
  return text;
}

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class HttpServerTest : public ::testing::Test {
 protected:
  void Start(HttpServerOptions options = {}) {
    server_ = std::make_unique<HttpServer>(options);
    server_->Route("GET", "/hello", [](const HttpRequest& req, HttpResponse& res) {
      res.SetContent("hello " + req.Param("name"), "text/plain");
    });
    server_->Route("POST", R"(/echo/([a-z]+))", [](const HttpRequest& req, HttpResponse& res) {
      res.SetContent(req.matches[1] + ":" + req.body, "text/plain");
    });
    server_->Route("GET", "/block", [this](const HttpRequest&, HttpResponse& res) {
      std::unique_lock<std::mutex> lock(mutex_);
      ++blocked_;
      changed_.notify_all();
      changed_.wait(lock, [this] { return released_; });
      res.SetContent("released", "text/plain");
    });
    server_->Route(
        "POST", "/urgent",
        [](const HttpRequest&, HttpResponse& res) { res.SetContent("acted", "text/plain"); },
        HttpLane::kUrgent);
    server_->Route("GET", "/stream", [](const HttpRequest&, HttpResponse& res) {
      auto left = std::make_shared<int>(3);
      res.content_type = "text/event-stream";
      res.stream = [left](HttpStreamSink& sink) {
        return (*left)-- > 0 && sink.Write("data: tick\n\n");
      };
    });
    server_->SetScreen([](const HttpRequest& req, HttpResponse& res) {
      if (req.method != "POST" || req.Header("Content-Type") == "application/json") return false;
      res.status = 415;
      res.SetContent("json only", "text/plain");
      return true;
    });
    const Status listening = server_->Listen("127.0.0.1", 0);
    ASSERT_TRUE(listening.ok()) << listening.ToString();
    port_ = server_->port();
  }
  void TearDown() override {
    Release();
    if (server_) server_->Stop();
  }
  void Release() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      released_ = true;
    }
    changed_.notify_all();
  }

  std::unique_ptr<HttpServer> server_;
  int port_ = 0;
  std::mutex mutex_;
  std::condition_variable changed_;
  int blocked_ = 0;
  bool released_ = false;
};

TEST_F(HttpServerTest, RoutesDecodesAndAnswersUnknownPathsWith404) {
  Start();
  auto res = RawRequest(port_, "GET", "/hello?name=a%20b&x");
  EXPECT_EQ(res.status, 200);
  EXPECT_EQ(res.body, "hello a b");
  res = RawRequest(port_, "POST", "/echo/abc", "{\"x\":1}");
  EXPECT_EQ(res.status, 200);
  EXPECT_EQ(res.body, "abc:{\"x\":1}");
  EXPECT_EQ(RawRequest(port_, "POST", "/echo/ABC", "{}").status, 404);
  EXPECT_EQ(RawRequest(port_, "GET", "/echo/abc").status, 404) << "the method is part of a route";
  EXPECT_EQ(RawRequest(port_, "GET", "/hello%00").status, 400) << "a decoded NUL";
}

TEST_F(HttpServerTest, KeepAliveServesPipelinedRequestsInOrder) {
  Start();
  const int fd = ConnectLoopback(port_);
  ASSERT_GE(fd, 0);
  const std::string one = "GET /hello?name=1 HTTP/1.1\r\nHost: x\r\n\r\n";
  const std::string two =
      "POST /echo/b HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: "
      "2\r\n\r\nhi";
  const std::string three = "GET /hello?name=3 HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
  ASSERT_TRUE(SendText(fd, one + two + three));
  const std::string text = ReadFor(fd, 5s);
  ::close(fd);
  const size_t a = text.find("hello 1"), b = text.find("b:hi"), c = text.find("hello 3");
  ASSERT_NE(a, std::string::npos) << text;
  ASSERT_NE(b, std::string::npos) << text;
  ASSERT_NE(c, std::string::npos) << text;
  EXPECT_LT(a, b);
  EXPECT_LT(b, c);
  EXPECT_EQ(Count(text, "HTTP/1.1 200"), 3u);
}

TEST_F(HttpServerTest, RefusesChunkedBodiesLargeBodiesAndLargeHeaders) {
  HttpServerOptions options;
  options.max_body_bytes = 100;
  options.max_header_bytes = 1024;
  Start(options);
  EXPECT_EQ(RawRequest(port_, "POST", "/echo/a", "", "Transfer-Encoding: chunked\r\n").status, 411);
  EXPECT_EQ(RawRequest(port_, "POST", "/echo/a", std::string(101, 'x')).status, 413);
  EXPECT_EQ(
      RawRequest(port_, "GET", "/hello", "", "X-Big: " + std::string(2000, 'y') + "\r\n").status,
      431);
  EXPECT_EQ(RawRequest(port_, "GET", "/hello", "", "Content-Length: 1x\r\n").status, 400);
  EXPECT_EQ(RawRequest(port_, "POST", "/echo/a", std::string(100, 'x')).status, 200);
}

TEST_F(HttpServerTest, RefusesSmugglingShapesOfContentLengthAndTransferEncoding) {
  Start();
  const auto send = [this](const std::string& request) {
    const int fd = ConnectLoopback(port_);
    SendText(fd, request);
    const std::string text = ReadFor(fd, 3s);
    ::close(fd);
    return text.substr(0, 12);
  };
  const std::string post = "POST /echo/a HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n";
  EXPECT_EQ(send(post + "Content-Length: 2\r\nContent-Length: 2\r\n\r\nhi"), "HTTP/1.1 400");
  EXPECT_EQ(send(post + "Transfer-Encoding:\r\nTransfer-Encoding: chunked\r\n\r\n0\r\n\r\n"),
            "HTTP/1.1 411");
  EXPECT_EQ(send(post + "Content-Length : 5\r\n\r\nhello"), "HTTP/1.1 400");
  EXPECT_EQ(send(post + "X-A: b\x01c\r\nContent-Length: 0\r\n\r\n"), "HTTP/1.1 400");
  EXPECT_EQ(send(post + " folded\r\nContent-Length: 0\r\n\r\n"), "HTTP/1.1 400");
  EXPECT_EQ(send("GET /" + std::string(3000, 'a') + " HTTP/1.1\r\nHost: x\r\n\r\n"),
            "HTTP/1.1 414");
}

TEST_F(HttpServerTest, GarbageAfterARequestIsRefusedAfterItsAnswer) {
  Start();
  for (const bool half_close : {false, true}) {
    const int fd = ConnectLoopback(port_);
    ASSERT_TRUE(SendText(fd, "GET /hello?name=ok HTTP/1.1\r\nHost: x\r\n\r\nGARBAGE\r\n\r\n"));
    if (half_close) ::shutdown(fd, SHUT_WR);
    const std::string text = ReadFor(fd, 3s);
    ::close(fd);
    EXPECT_NE(text.find("hello ok"), std::string::npos) << text;
    EXPECT_NE(text.find("HTTP/1.1 400"), std::string::npos) << text;
  }
  EXPECT_EQ(RawRequest(port_, "GET", "/hello").status, 200) << "the server lives on";
}

TEST_F(HttpServerTest, AnExpectedBodyIsInvitedWith100Continue) {
  Start();
  const int fd = ConnectLoopback(port_);
  ASSERT_TRUE(SendText(fd,
                       "POST /echo/a HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                       "Content-Length: 4\r\nExpect: 100-continue\r\n\r\n"));
  EXPECT_EQ(ReadFor(fd, 500ms), "HTTP/1.1 100 Continue\r\n\r\n");
  ASSERT_TRUE(SendText(fd, "body"));
  EXPECT_NE(ReadFor(fd, 500ms).find("a:body"), std::string::npos);
  ::close(fd);
}

TEST_F(HttpServerTest, ClientsThatDoNotReadTheirAnswersDelayNoUrgentRequest) {
  Start();
  // Each sends thousands of refused (415) and normal requests and reads nothing.
  std::string flood;
  for (int i = 0; i < 2000; ++i)
    flood +=
        "POST /urgent HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\n\r\n{}"
        "GET /hello?name=" +
        std::string(200, 'x') + " HTTP/1.1\r\nHost: x\r\n\r\n";
  std::vector<int> floods;
  for (int i = 0; i < 16; ++i) {
    floods.push_back(ConnectLoopback(port_));
    ::send(floods.back(), flood.data(), flood.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  }
  std::this_thread::sleep_for(300ms);
  for (int i = 0; i < 5; ++i) {
    const auto urgent = RawRequest(port_, "POST", "/urgent", "{}", "", 10s);
    EXPECT_EQ(urgent.status, 200);
    EXPECT_LT(urgent.seconds, 2.0) << "a liveness bound: blocked writes would hold it 5 s each";
  }
  EXPECT_EQ(RawRequest(port_, "GET", "/hello", "", "", 10s).status, 200);
  for (int fd : floods) ::close(fd);
}

TEST_F(HttpServerTest, ABurstOfConnectionsAfterARequestDoesNotEvictIt) {
  HttpServerOptions options;
  options.max_connections = 100;
  options.max_connections_per_client = 100;
  Start(options);
  const int urgent = ConnectLoopback(port_);
  ASSERT_TRUE(SendText(urgent,
                       "POST /urgent HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                       "Content-Length: 2\r\nConnection: close\r\n\r\n{}"));
  std::vector<int> burst;
  for (int i = 0; i < 500; ++i) burst.push_back(ConnectLoopback(port_));
  EXPECT_NE(ReadFor(urgent, 10s).find("acted"), std::string::npos);
  ::close(urgent);
  for (int fd : burst) ::close(fd);
}

TEST_F(HttpServerTest, DropsSlowHeaderAndIdleConnections) {
  HttpServerOptions options;
  options.request_timeout = 300ms;
  options.idle_timeout = 600ms;
  Start(options);
  const int slow = ConnectLoopback(port_);
  const int idle = ConnectLoopback(port_);
  ASSERT_TRUE(SendText(slow, "GET /hel"));
  // One byte every 100 ms: the request never completes within 300 ms of its first byte.
  bool slow_closed = false;
  for (int i = 0; i < 30 && !slow_closed; ++i) {
    std::this_thread::sleep_for(100ms);
    slow_closed = PeerClosed(slow) || !SendText(slow, "l");
  }
  EXPECT_TRUE(slow_closed) << "a slow-header client is dropped";
  bool idle_closed = false;
  for (int i = 0; i < 50 && !idle_closed; ++i) {
    std::this_thread::sleep_for(100ms);
    idle_closed = PeerClosed(idle);
  }
  EXPECT_TRUE(idle_closed) << "a connection that sends nothing is closed";
  ::close(slow);
  ::close(idle);
  const HttpServerStats stats = server_->Stats();
  EXPECT_GE(stats.closed_slow, 1u);
  EXPECT_GE(stats.closed_idle, 1u);
}

TEST_F(HttpServerTest, ANewConnectionOverTheBoundClosesTheOldestWaitingOne) {
  HttpServerOptions options;
  options.max_connections = 50;
  options.max_connections_per_client = 40;
  Start(options);
  std::vector<int> held;
  for (int i = 0; i < 120; ++i) held.push_back(ConnectLoopback(port_));
  const auto res = RawRequest(port_, "GET", "/hello?name=new", "", "", 10s);
  EXPECT_EQ(res.status, 200) << "the newest connection is read";
  std::this_thread::sleep_for(200ms);
  EXPECT_TRUE(PeerClosed(held.front())) << "the oldest idle connection made room";
  EXPECT_FALSE(PeerClosed(held.back()));
  EXPECT_LE(server_->Stats().open_connections, 41);
  EXPECT_GE(server_->Stats().closed_evicted, 80u);
  for (int fd : held) ::close(fd);
}

TEST_F(HttpServerTest, UrgentRoutesAreServedWhileEveryWorkerIsBusy) {
  HttpServerOptions options;
  options.normal_workers = 2;
  Start(options);
  std::vector<std::thread> clients;
  for (int i = 0; i < 4; ++i)
    clients.emplace_back([this] { RawRequest(port_, "GET", "/block", "", "", 60s); });
  {
    std::unique_lock<std::mutex> lock(mutex_);
    ASSERT_TRUE(changed_.wait_for(lock, 30s, [this] { return blocked_ == 2; }));
  }
  // Both workers are held and two requests wait behind them; the urgent one does not.
  const auto urgent = RawRequest(port_, "POST", "/urgent", "{}", "", 10s);
  EXPECT_EQ(urgent.status, 200);
  EXPECT_EQ(urgent.body, "acted");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_EQ(blocked_, 2) << "the normal lane was still held while the urgent route answered";
  }
  Release();
  for (std::thread& t : clients) t.join();
}

TEST_F(HttpServerTest, StreamsInChunksUntilTheWriterEnds) {
  Start();
  const auto res = RawRequest(port_, "GET", "/stream", "", "", 10s);
  EXPECT_EQ(res.status, 200);
  EXPECT_NE(res.head.find("Transfer-Encoding: chunked"), std::string::npos);
  EXPECT_EQ(Count(res.body, "data: tick"), 3u);
  EXPECT_NE(res.body.find("\r\n0\r\n\r\n"), std::string::npos) << "the last chunk";
}

TEST_F(HttpServerTest, ThousandsOfIdleConnectionsCostNoThreadAndDoNotDelayARequest) {
  if (!hairrig_test::AllowOpenFiles(6000))
    GTEST_SKIP() << "the open-file limit is below 6000; raise it (ulimit -n) to run this test";
  Start();
  const auto threads = [] {
    return std::distance(std::filesystem::directory_iterator("/proc/self/task"),
                         std::filesystem::directory_iterator{});
  };
  const auto threads_before = threads();
  std::vector<int> held;
  for (int i = 0; i < 2000; ++i) held.push_back(ConnectLoopback(port_));
  const auto res = RawRequest(port_, "POST", "/urgent", "{}", "", 10s);
  EXPECT_EQ(threads(), threads_before) << "connections cost no thread";
  EXPECT_EQ(res.status, 200);
  EXPECT_EQ(RawRequest(port_, "GET", "/hello", "", "", 10s).status, 200);
  EXPECT_GE(server_->Stats().open_connections, 2000) << "held, not dropped";
  for (int fd : held) ::close(fd);
}

TEST(HttpServerOptionsTest, CheckNamesTheBadField) {
  HttpServerOptions options;
  EXPECT_TRUE(options.Check().ok());
  options.max_connections = 0;
  EXPECT_NE(options.Check().message().find("max_connections"), std::string::npos);
  options = {};
  options.request_timeout = 0ms;
  EXPECT_NE(options.Check().message().find("request_timeout"), std::string::npos);
}

}  // namespace
}  // namespace hairrig
