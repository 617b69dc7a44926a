// whiskeye-viewer as shipped: live behind the real lcm-logplayer and a live slamd, the page rendered
// by headless Chromium (a screenshot kept in the build tree); its HTTP surface against path traversal,
// too many clients and a client that stops reading, clients sending or reading slowly, header floods,
// many ranges, a foreign Host; --log with the slider's time and a log that gets shorter while served;
// the command line.
// Runs inside a private network namespace (NETNS in CMake): LCM over udpm:// reaches nothing outside.
#include "scratch.h"
#include "slamd_files.h"
#include "subprocess.h"

#include "whiskeye/common/bus.h"
#include "whiskeye/common/channels.h"

#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>
#include <whiskeye/vita_pose_t.hpp>

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <nlohmann/json.hpp>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::read_slamd_output;
using testing::Subprocess;
using testing::wait_until;
using ::testing::HasSubstr;
using ::testing::Not;

const std::string kViewer = VIEWER_EXE;
const std::string kConfig = WHISKEYE_SOURCE_DIR "/config/slam.yaml";

// Starts the viewer and waits for the line naming where it serves; the port it bound.
int start_viewer(Subprocess& viewer) {
  int port = -1;
  const bool up = wait_until(
      [&] {
        std::smatch m;
        const std::string out = viewer.output();
        if (!std::regex_search(out, m, std::regex("serving http://127\\.0\\.0\\.1:([0-9]+)/"))) return false;
        port = std::stoi(m[1]);
        return true;
      },
      20.0);
  EXPECT_TRUE(up) << viewer.output();
  return port;
}

json get_json(int port, const std::string& path) {
  httplib::Client client("127.0.0.1", port);
  client.set_connection_timeout(5, 0);  // httplib's default is 300 s: the whole test's time-out
  client.set_read_timeout(5, 0);
  const auto res = client.Get(path.c_str());
  if (!res || res->status != 200) return nullptr;
  return json::parse(res->body, nullptr, false);
}

// A TCP connection to the viewer that sends exactly `request` (no client library normalises it).
class RawClient {
 public:
  explicit RawClient(int port, int rcvbuf = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (rcvbuf > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    timeval tv{5, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    // connect() bounded too (SO_SNDTIMEO, on Linux; a full accept queue retries the SYN for ~2 min),
    // writes not: the flood tests write until the viewer closes.
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    const timeval forever{0, 0};
    ::setsockopt(fd_, SOL_SOCKET, SO_SNDTIMEO, &forever, sizeof forever);
  }
  ~RawClient() { ::close(fd_); }
  bool connected() const { return connected_; }
  void send(const std::string& request) { EXPECT_EQ(::write(fd_, request.data(), request.size()), static_cast<ssize_t>(request.size())); }
  // Whether something arrives to be read within `timeout_ms`.
  bool readable(int timeout_ms) {
    pollfd p{fd_, POLLIN, 0};
    return ::poll(&p, 1, timeout_ms) == 1;
  }
  // False once the peer has closed or reset the connection (no SIGPIPE).
  bool try_send(const std::string& bytes) {
    return ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
  }
  // Reads until the peer closes, `until` appears, 5 s pass without a byte, or 30 s in all (a stream
  // that goes on without `until`).
  std::string read(const std::string& until = "") {
    std::string out;
    char buf[65536];
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < deadline) {
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) break;
      out.append(buf, static_cast<std::size_t>(n));
      if (!until.empty() && out.find(until) != std::string::npos) break;
    }
    return out;
  }
  // One request, the whole answer (Connection: close).
  static std::string exchange(int port, const std::string& request_line, const std::string& body = "",
                              const std::string& headers = "Host: 127.0.0.1\r\n") {
    RawClient c(port);
    c.send(request_line + "\r\n" + headers + "Connection: close\r\n" +
           (body.empty() ? "" : "Content-Length: " + std::to_string(body.size()) + "\r\n") + "\r\n" + body);
    return c.read();
  }

 private:
  int fd_ = -1;
  bool connected_ = false;
};

std::string chromium(const std::vector<std::string>& extra, const std::string& url) {
  // Root in CI: Chromium's sandbox needs an unprivileged user; the page is our own.
  std::vector<std::string> argv{"chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                                "--disable-dev-shm-usage", "--hide-scrollbars", "--window-size=1280,1000",
                                "--virtual-time-budget=8000"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  argv.push_back(url);
  Subprocess c(argv, "", {"HOME=" + testing::scratch_dir("chromium_home")});
  EXPECT_EQ(c.wait(90), 0) << c.output();
  return c.output();
}

// Headless Chromium driven over WebDriver (chromedriver), for a page that keeps a stream open: the
// live page's Server-Sent Events never let `chromium --dump-dom --virtual-time-budget` finish.
class Browser {
 public:
  Browser() : driver_({"chromedriver", "--port=" + std::to_string(kPort)}, "", {"HOME=" + testing::scratch_dir("chromedriver_home")}) {
    // A new session starts Chromium: seconds on a loaded runner (beside a TCG guest), where
    // httplib's default 5 s read time-out made the session null once in two runs.
    client_.set_connection_timeout(5, 0);
    client_.set_read_timeout(60, 0);
    EXPECT_TRUE(wait_until([&] { return client_.Get("/status") != nullptr; }, 20.0)) << driver_.output();
    const json caps = {{"capabilities",
                        {{"alwaysMatch",
                          {{"goog:chromeOptions",
                            {{"binary", "/usr/bin/chromium"},
                             // Root in CI: Chromium's sandbox needs an unprivileged user; the page is our own.
                             {"args", {"--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                                       "--hide-scrollbars", "--window-size=1280,1150"}}}}}}}}};
    const json session = call("POST", "/session", caps);
    session_ = session.is_object() && session.contains("sessionId") ? session["sessionId"].get<std::string>() : "";
    EXPECT_FALSE(session_.empty()) << session.dump() << driver_.output();
  }
  ~Browser() {
    if (!session_.empty()) client_.Delete(("/session/" + session_).c_str());
    driver_.stop(5, SIGTERM);
  }
  void open(const std::string& url) { call("POST", "/session/" + session_ + "/url", {{"url", url}}); }
  // The value of a JavaScript expression in the page.
  json eval(const std::string& expression) {
    return call("POST", "/session/" + session_ + "/execute/sync",
                {{"script", "return " + expression + ";"}, {"args", json::array()}});
  }
  std::string text(const std::string& id) {
    const json v = eval("(document.getElementById('" + id + "') || {}).textContent");
    return v.is_string() ? v.get<std::string>() : "";
  }
  std::string dom() {
    const json v = call("GET", "/session/" + session_ + "/source", nullptr);
    return v.is_string() ? v.get<std::string>() : "";
  }
  void screenshot(const std::string& png) {
    const json v = call("GET", "/session/" + session_ + "/screenshot", nullptr);
    ASSERT_TRUE(v.is_string()) << v.dump();
    std::ofstream(png, std::ios::binary) << base64_decode(v.get<std::string>());
  }

 private:
  static constexpr int kPort = 9515;
  json call(const std::string& method, const std::string& path, const json& body) {
    const auto res = method == "GET" ? client_.Get(path.c_str())
                                     : client_.Post(path.c_str(), body.dump(), "application/json");
    if (!res) return nullptr;
    const json answer = json::parse(res->body, nullptr, false);
    return answer.is_object() && answer.contains("value") ? answer["value"] : json(nullptr);
  }
  static std::string base64_decode(const std::string& in) {
    std::string out;
    int bits = 0, value = 0;
    for (char c : in) {
      int d = -1;
      if (c >= 'A' && c <= 'Z') d = c - 'A';
      else if (c >= 'a' && c <= 'z') d = c - 'a' + 26;
      else if (c >= '0' && c <= '9') d = c - '0' + 52;
      else if (c == '+') d = 62;
      else if (c == '/') d = 63;
      if (d < 0) continue;
      value = (value << 6) | d;
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        out.push_back(static_cast<char>((value >> bits) & 0xff));
      }
    }
    return out;
  }
  Subprocess driver_;
  httplib::Client client_{"127.0.0.1", kPort};
  std::string session_;
};

// The text of the element with `id` in a dumped DOM, or "".
std::string element_text(const std::string& dom, const std::string& id) {
  std::smatch m;
  if (!std::regex_search(dom, m, std::regex("id=\"" + id + "\"[^>]*>([^<]*)<"))) return "";
  return m[1];
}

class ViewerBinary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::path(testing::scratch_dir("viewer_binary"));
    sim_log_ = (dir_ / "sim.lcmlog").string();
    Subprocess sim({VITA_SIM_EXE, "--world", WHISKEYE_SOURCE_DIR "/config/worlds/aliased_arena.yaml", "--robot",
                    WHISKEYE_SOURCE_DIR "/config/robot.yaml", "--duration", "12", "--seed", "5", "--quiet",
                    "--output", sim_log_});
    ASSERT_EQ(sim.wait(120), 0) << sim.output();
  }
  static fs::path dir_;
  static std::string sim_log_;
};
fs::path ViewerBinary::dir_;
std::string ViewerBinary::sim_log_;

TEST_F(ViewerBinary, LivePageRenderedInChromiumShowsTheMapsExperienceCountAndTheLatestEvent) {
  ASSERT_NE(std::getenv("WHISKEYE_NETNS"), nullptr) << "runs in its own network namespace (netns-run)";
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0"});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);

  // What the viewer should end up showing, as an LCM subscriber of our own sees it.
  LcmBus bus;
  DecodeErrors errors;
  vita_map_t last_map;
  vita_event_t last_event;
  int maps = 0, events = 0;
  subscribe<vita_map_t>(bus, channels::kVitaMap, [&](const vita_map_t& m) {
    last_map = m;
    ++maps;
  }, errors);
  subscribe<vita_event_t>(bus, channels::kVitaEvent, [&](const vita_event_t& m) {
    last_event = m;
    ++events;
  }, errors);

  Subprocess slamd({SLAMD_EXE, "--config", kConfig, "--state-dir", (dir_ / "live_state").string(), "--fresh"});
  ASSERT_TRUE(wait_until([&] { return slamd.output().find("running in vita mode") != std::string::npos; }, 20))
      << slamd.output();
  Subprocess player({"lcm-logplayer", "--speed", "2", sim_log_});
  while (player.running()) bus.handle_timeout(50);
  EXPECT_EQ(player.wait(1), 0) << player.output();
  for (int i = 0; i < 40; ++i) bus.handle_timeout(50);
  ASSERT_GT(maps, 0) << slamd.output();
  ASSERT_GT(events, 0);
  ASSERT_GE(last_map.num_experiences, 2);

  // The viewer saw the same (its own socket; loopback with a 4 MB buffer loses nothing here).
  json status;
  ASSERT_TRUE(wait_until(
      [&] {
        status = get_json(port, "/status");
        return status.is_object() && status["num_experiences"] == last_map.num_experiences;
      },
      10))
      << status.dump(2);
  EXPECT_EQ(status["meta"]["decode_errors"], 0) << status.dump(2);
  EXPECT_GT(status["meta"]["messages"]["CAMERA"].get<int>(), 0);
  EXPECT_GT(status["meta"]["messages"]["WHISK_CYCLE"].get<int>(), 0);
  bool slamd_status = false;
  for (const auto& d : status["status"]) slamd_status |= d["name"] == "slamd";
  EXPECT_TRUE(slamd_status) << "SLAM_STATUS shown";

  // The page as a browser renders it: the whole state, then the live stream.
  Browser browser;
  browser.open("http://127.0.0.1:" + std::to_string(port) + "/");
  EXPECT_TRUE(wait_until([&] { return browser.text("connection") == "connected"; }, 20)) << browser.text("connection");
  EXPECT_TRUE(wait_until([&] { return browser.text("num-experiences") == std::to_string(last_map.num_experiences); }, 10))
      << browser.text("num-experiences") << " experiences shown, " << last_map.num_experiences << " in the last VITA_MAP";
  EXPECT_EQ(browser.text("current-experience"), std::to_string(last_map.current_experience_id));
  const std::string type = last_event.type == vita_event_t::NEW_EXPERIENCE ? "new experience"
                           : last_event.type == vita_event_t::RELOCALISE  ? "re-localised"
                                                                          : "same experience";
  EXPECT_EQ(browser.text("event-type"), type);
  EXPECT_THAT(browser.text("event-detail"), HasSubstr("cycle " + std::to_string(last_event.cycle) + ":"));
  const std::string dom = browser.dom();
  EXPECT_THAT(dom, HasSubstr("data-name=\"slamd\"")) << "a status card per daemon";
  EXPECT_THAT(dom, HasSubstr("src=\"/api/camera.jpg?frame=")) << "the latest camera frame";
  // The frame is fetched after the DOM names it: its decoded width once loaded (read at once, it was 0
  // now and then on a loaded machine).
  EXPECT_TRUE(wait_until([&] { return browser.eval("document.getElementById('camera').naturalWidth").get<int>() == 320; }, 10))
      << "a decoded JPEG";

  // Live: one more map, and the open page shows it without reloading.
  vita_map_t more = last_map;
  experience_t extra{};
  extra.id = 10000;
  more.experiences.push_back(extra);
  more.num_experiences = static_cast<int32_t>(more.experiences.size());
  publish(bus, channels::kVitaMap, more);
  EXPECT_TRUE(wait_until([&] { return browser.text("num-experiences") == std::to_string(more.num_experiences); }, 10));
  EXPECT_EQ(browser.text("localisation"), "tracking");
  // A link the back end revoked is counted on the page, and slamd LOCALISING is shown as such.
  more.links.push_back(link_t{});
  more.links.back().from_id = more.experiences.front().id;
  more.links.back().to_id = extra.id;
  more.links.back().revoked = true;
  more.num_links = static_cast<int32_t>(more.links.size());
  publish(bus, channels::kVitaMap, more);
  EXPECT_TRUE(wait_until([&] { return browser.text("num-revoked") == "1"; }, 10)) << browser.text("num-revoked");
  vita_pose_t lost{};
  lost.utime = last_map.utime + 1'000'000;
  lost.mode = vita_pose_t::MODE_VITA;
  lost.localisation = vita_pose_t::LOCALISATION_LOCALISING;
  publish(bus, channels::kVitaPose, lost);
  EXPECT_TRUE(wait_until([&] { return browser.text("localisation") == "LOCALISING"; }, 10)) << browser.text("localisation");

  // A screenshot for people: build/tests/tools/viewer_results/viewer-live.png.
  fs::create_directories(VIEWER_RESULTS_DIR);
  const std::string png = std::string(VIEWER_RESULTS_DIR) + "/viewer-live.png";
  fs::remove(png);
  browser.screenshot(png);
  ASSERT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 20'000u) << "a rendered page, not a blank one";
  std::printf("screenshot: %s\n", png.c_str());

  EXPECT_EQ(slamd.stop(20, SIGTERM), 0) << slamd.output();
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
  EXPECT_THAT(viewer.output(), HasSubstr("whiskeye-viewer: stopped"));
}

TEST_F(ViewerBinary, ServesNoPathOutsideItsOwnFilesAndBindsLoopbackByDefault) {
  Subprocess viewer({kViewer});  // the default address
  const int port = start_viewer(viewer);
  ASSERT_EQ(port, 8088) << viewer.output();

  EXPECT_THAT(RawClient::exchange(port, "GET / HTTP/1.1"), HasSubstr("HTTP/1.1 200"));
  EXPECT_THAT(RawClient::exchange(port, "GET /viewer.js HTTP/1.1"), HasSubstr("text/javascript"));
  for (const std::string target :
       {"/../etc/passwd", "/../../../../../../etc/passwd", "/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "/..%2f..%2f..%2fetc%2fpasswd",
        "/%2e%2e%2f%2e%2e%2fetc%2fpasswd", "//etc/passwd", "/etc/passwd", "/viewer.js/../../../../etc/passwd",
        "/./../etc/passwd", "/index.html%00", "/%00../../etc/passwd", "/proc/self/environ", "/..\\..\\etc\\passwd",
        "http://127.0.0.1/etc/passwd", "/%252e%252e/etc/passwd", "/api/../../etc/passwd", "/web/index.html",
        "/CMakeLists.txt", "/tools/viewer/web/viewer.js"}) {
    const std::string answer = RawClient::exchange(port, "GET " + target + " HTTP/1.1");
    EXPECT_THAT(answer, Not(HasSubstr("HTTP/1.1 200"))) << target;
    EXPECT_THAT(answer, Not(HasSubstr("root:"))) << target;
    EXPECT_THAT(answer, Not(HasSubstr("PATH="))) << target;
    EXPECT_THAT(answer, HasSubstr("X-Content-Type-Options: nosniff")) << target << "\n" << answer;
  }
  // Read-only: no method but GET (and HEAD) does anything.
  for (const std::string method : {"POST", "PUT", "DELETE", "PATCH"}) {
    const std::string answer = RawClient::exchange(port, method + " /api/snapshot HTTP/1.1", "{}");
    EXPECT_THAT(answer, Not(HasSubstr("HTTP/1.1 200"))) << method;
  }
  // Still serving after all of it.
  EXPECT_TRUE(get_json(port, "/status").is_object());
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
}

TEST_F(ViewerBinary, ASlowClientDropsUpdatesCountedWithoutHoldingBackOthersAndClientsAreBounded) {
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--max-clients", "3", "--queue", "4", "--update-ms", "20"});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);

  // A client that asks for the stream and never reads, with a tiny receive buffer: the viewer's
  // writes to it block, its queue fills.
  RawClient slow(port, 2048);
  ASSERT_TRUE(slow.connected());
  slow.send("GET /api/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  // A client that reads everything.
  std::atomic<int> good_deltas{0};
  std::atomic<bool> stop{false};
  std::thread good([&] {
    RawClient c(port);
    c.send("GET /api/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    std::string tail;
    while (!stop) {
      std::string got = c.read("event: delta");
      if (got.empty()) continue;
      tail += got;
      std::size_t at = 0;
      while ((at = tail.find("event: delta", at)) != std::string::npos) {
        ++good_deltas;
        at += 12;
      }
      tail = tail.substr(tail.size() > 11 ? tail.size() - 11 : 0);  // a marker split across reads
    }
  });
  // Ends the reader however the test ends: an ASSERT returning with the thread joinable would abort
  // the whole binary (std::terminate) and leave nothing but a core.
  struct EndOnReturn {
    std::atomic<bool>& stop;
    std::thread& thread;
    void operator()() {
      stop = true;
      if (thread.joinable()) thread.join();
    }
    ~EndOnReturn() { (*this)(); }
  } end_good{stop, good};

  // Big updates, fast: a map of 3000 experiences (~100 kB of JSON) and a pose, every 20 ms, for 4 s.
  LcmBus bus;
  vita_map_t map{};
  map.mode = vita_pose_t::MODE_VITA;
  for (int i = 0; i < 3000; ++i) {
    experience_t e{};
    e.id = i;
    e.x = 0.001 * i;
    e.y = 0.002 * i;
    map.experiences.push_back(e);
  }
  map.num_experiences = 3000;
  const auto t0 = std::chrono::steady_clock::now();
  int n = 0;
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(4)) {
    map.utime = 1'700'000'000'000'000 + n * 20'000;
    map.current_experience_id = n % 3000;
    publish(bus, channels::kVitaMap, map);
    vita_pose_t pose{};
    pose.utime = map.utime;
    pose.x = 0.01 * n;
    publish(bus, channels::kVitaPose, pose);
    ++n;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  // The viewer still answers at once, and says what the slow client lost.
  const auto asked = std::chrono::steady_clock::now();
  const json status = get_json(port, "/status");
  EXPECT_LT(std::chrono::steady_clock::now() - asked, std::chrono::seconds(2));
  ASSERT_TRUE(status.is_object());
  EXPECT_GT(status["dropped"].get<int64_t>(), 0) << status.dump(2);
  EXPECT_GT(status["updates"].get<int64_t>(), 50) << status.dump(2);
  int64_t most_dropped = 0, least_dropped = INT64_MAX;
  for (const auto& c : status["per_client"]) {
    most_dropped = std::max(most_dropped, c["dropped"].get<int64_t>());
    least_dropped = std::min(least_dropped, c["dropped"].get<int64_t>());
  }
  EXPECT_GT(most_dropped, 0) << "the slow client";
  EXPECT_GT(good_deltas.load(), 50) << "the client that reads kept getting updates";

  // Bounded clients: two are connected; a third fits, a fourth is refused.
  RawClient third(port);
  third.send("GET /api/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_THAT(third.read("event: snapshot"), HasSubstr("event: snapshot"));
  const std::string fourth = RawClient::exchange(port, "GET /api/events HTTP/1.1");
  EXPECT_THAT(fourth, HasSubstr("HTTP/1.1 503"));
  EXPECT_GE(get_json(port, "/status")["refused"].get<int>(), 1);

  end_good();
  EXPECT_EQ(viewer.stop(15, SIGTERM), 0) << viewer.output();
}

TEST_F(ViewerBinary, LogModeShowsTheStateAtTheSlidersTime) {
  const std::string slam_log = (dir_ / "slam.lcmlog").string();
  {
    Subprocess replay({SLAMD_EXE, "--replay", sim_log_, "--output", slam_log, "--config", kConfig});
    ASSERT_EQ(replay.wait(120), 0) << replay.output();
  }
  const testing::SlamdOutput out = read_slamd_output(slam_log);
  ASSERT_GE(out.maps.size(), 2u);
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", slam_log});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);
  const json status = get_json(port, "/status");
  ASSERT_TRUE(status.is_object());
  EXPECT_EQ(status["mode"], "log");
  const int64_t start = status["log"]["start"], end = status["log"]["end"];
  ASSERT_LT(start, end);

  const json at_end = get_json(port, "/api/snapshot?t=" + std::to_string(end));
  EXPECT_EQ(at_end["map"]["num_experiences"], out.maps.back().num_experiences);
  EXPECT_EQ(at_end["event"]["last"]["cycle"], out.events.back().cycle);
  // Back to the first map's log time: the state then, not the end's.
  int64_t first_map_at = 0;
  {
    LogReader reader(slam_log);
    LogEvent ev;
    while (first_map_at == 0 && reader.next(ev)) {
      if (ev.channel == channels::kVitaMap) first_map_at = ev.utime;
    }
  }
  const json at_first = get_json(port, "/api/snapshot?t=" + std::to_string(first_map_at));
  ASSERT_TRUE(at_first["map"].is_object()) << at_first.dump();
  EXPECT_EQ(at_first["map"]["num_experiences"], out.maps.front().num_experiences);
  const json before = get_json(port, "/api/snapshot?t=" + std::to_string(start - 1));
  EXPECT_TRUE(before["map"].is_null());
  // A log has no live stream.
  EXPECT_THAT(RawClient::exchange(port, "GET /api/events HTTP/1.1"), HasSubstr("HTTP/1.1 404"));

  // The page opens at the end of the log.
  const std::string url = "http://127.0.0.1:" + std::to_string(port) + "/";
  const std::string dom = chromium({"--dump-dom"}, url);
  EXPECT_EQ(element_text(dom, "num-experiences"), std::to_string(out.maps.back().num_experiences)) << dom.substr(0, 3000);
  EXPECT_THAT(element_text(dom, "event-detail"), HasSubstr("cycle " + std::to_string(out.events.back().cycle) + ":"));
  fs::create_directories(VIEWER_RESULTS_DIR);
  chromium({"--screenshot=" + std::string(VIEWER_RESULTS_DIR) + "/viewer-log.png"}, url);
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
}


// An LCM log holding one VITA_MAP of `n` experiences (220,000: a snapshot of 4.7 MB).
std::string write_big_map_log(const fs::path& dir, int n) {
  const std::string path = (dir / ("map" + std::to_string(n) + ".lcmlog")).string();
  LogWriterBus log(path);
  vita_map_t map{};
  map.mode = vita_pose_t::MODE_VITA;
  for (int i = 0; i < n; ++i) {
    experience_t e{};
    e.id = i;
    e.x = 0.001 * i;
    e.y = 0.002 * i;
    map.experiences.push_back(e);
  }
  map.num_experiences = n;
  map.utime = 1'700'000'000'000'000;
  log.set_time(map.utime);
  publish(log, channels::kVitaMap, map);
  return path;
}

TEST_F(ViewerBinary, ClientsSendingOrReadingSlowlyHoldBackNoOtherRequest) {
  const std::string log = write_big_map_log(dir_, 220000);
  // --max-clients 1: five workers, fewer than the slow clients below.
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", log, "--max-clients", "1"});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);
  const std::string big = RawClient::exchange(port, "GET /api/snapshot?t=99999999999999999 HTTP/1.1");
  ASSERT_THAT(big, HasSubstr("HTTP/1.1 200"));
  ASSERT_GT(big.size(), 4'500'000u) << "the answer must outgrow a socket's largest buffer (net.ipv4.tcp_wmem)";

  // 8 clients asking for that answer and never reading it (2 kB receive buffers); once each has its
  // first bytes, its answer is made.
  std::vector<std::unique_ptr<RawClient>> readers;
  for (int i = 0; i < 8; ++i) {
    readers.push_back(std::make_unique<RawClient>(port, 2048));
    readers.back()->send("GET /api/snapshot?t=99999999999999999 HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  }
  for (auto& r : readers) ASSERT_TRUE(r->readable(60'000));
  // 30 clients sending a request one byte every 100 ms.
  std::vector<std::unique_ptr<RawClient>> senders;
  for (int i = 0; i < 30; ++i) senders.push_back(std::make_unique<RawClient>(port));
  const auto opened = std::chrono::steady_clock::now();
  std::atomic<bool> stop{false};
  std::thread drip([&] {
    const std::string request = "GET /status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + std::string(200, 'b');
    for (std::size_t i = 0; i < request.size() && !stop; ++i) {
      for (auto& c : senders) c->try_send(request.substr(i, 1));
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  // Every other request is answered at once, again and again, while the slow clients go on.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  json status;
  for (int i = 0; i < 6; ++i) {
    const auto asked = std::chrono::steady_clock::now();
    status = get_json(port, "/status");
    EXPECT_LT(std::chrono::steady_clock::now() - asked, std::chrono::seconds(1)) << "request " << i;
    EXPECT_TRUE(status.is_object()) << "request " << i;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  const bool in_time = std::chrono::steady_clock::now() - opened < std::chrono::seconds(5);
  // A request not whole 5 s after its connection opened gets 408 and is closed.
  const std::string cut = senders.front()->read();
  stop = true;
  drip.join();
  ASSERT_TRUE(in_time) << "the checks above took longer than the slow senders may";
  ASSERT_TRUE(status.is_object());
  // The answers the readers do not take wait in the viewer, not in its workers.
  EXPECT_GT(status["http"]["buffered_bytes"].get<int64_t>(), 0) << status.dump(2);
  EXPECT_THAT(cut, HasSubstr("HTTP/1.1 408"));
  EXPECT_TRUE(wait_until([&] { return get_json(port, "/status")["http"]["timed_out"].get<int64_t>() >= 30; }, 10.0))
      << get_json(port, "/status").dump(2);
  EXPECT_EQ(viewer.stop(15, SIGTERM), 0) << viewer.output();
}

TEST_F(ViewerBinary, AFloodOfHeadersIsRefusedWithoutGrowingItsMemory) {
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", sim_log_});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);
  ASSERT_TRUE(get_json(port, "/status").is_object());
  const int64_t before = testing::proc_status_kb(viewer.pid(), "VmRSS");
  // 100 MB of header lines on one connection: refused (431) within the first 32 kB, then closed.
  RawClient flood(port);
  flood.try_send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n");
  std::string lines;
  for (int i = 0; i < 10000; ++i) lines += "X-aaaa: b\r\n";
  std::size_t sent = 0;
  while (sent < 100'000'000 && flood.try_send(lines)) sent += lines.size();
  EXPECT_LT(sent, 100'000'000u) << "the viewer kept reading headers";
  EXPECT_THAT(flood.read(), HasSubstr("HTTP/1.1 431"));
  const int64_t after = testing::proc_status_kb(viewer.pid(), "VmRSS");
  EXPECT_LT(after - before, 8 * 1024) << before << " kB before, " << after << " kB after";
  // Too many fields, each short: refused too.
  std::string fields = "Host: 127.0.0.1\r\n";
  for (int i = 0; i < 150; ++i) fields += "X-" + std::to_string(i) + ": b\r\n";
  EXPECT_THAT(RawClient::exchange(port, "GET /status HTTP/1.1", "", fields), HasSubstr("HTTP/1.1 431"));
  // A body it would not read, announced or chunked: refused before it is sent.
  EXPECT_THAT(RawClient::exchange(port, "GET /status HTTP/1.1", "", "Host: 127.0.0.1\r\nContent-Length: 100000000\r\n"),
              HasSubstr("HTTP/1.1 413"));
  EXPECT_THAT(RawClient::exchange(port, "GET /status HTTP/1.1", "", "Host: 127.0.0.1\r\nTransfer-Encoding: chunked\r\n"),
              HasSubstr("HTTP/1.1 413"));
  EXPECT_TRUE(get_json(port, "/status").is_object());
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
}

TEST_F(ViewerBinary, RangesAreIgnoredAndEveryAnswerIsWhole) {
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", sim_log_});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);
  const auto body_size = [](const std::string& answer) {
    const auto at = answer.find("\r\n\r\n");
    return at == std::string::npos ? std::string::npos : answer.size() - at - 4;
  };
  const std::string whole = RawClient::exchange(port, "GET /viewer.js HTTP/1.1");
  ASSERT_THAT(whole, HasSubstr("HTTP/1.1 200"));
  // 2,700 ranges of the whole file in an 8 kB request: one copy of it, not 2,700.
  std::string ranges = "bytes=0-";
  for (int i = 1; i < 2700; ++i) ranges += ",0-";
  const std::string many = RawClient::exchange(port, "GET /viewer.js HTTP/1.1", "", "Host: 127.0.0.1\r\nRange: " + ranges + "\r\n");
  EXPECT_THAT(many, HasSubstr("HTTP/1.1 200"));
  EXPECT_EQ(body_size(many), body_size(whole));
  // A range past the end of the camera frame: the whole frame, nothing beyond it.
  const std::string jpeg = RawClient::exchange(port, "GET /api/camera.jpg?t=99999999999999999 HTTP/1.1");
  ASSERT_THAT(jpeg, HasSubstr("HTTP/1.1 200"));
  const std::string past = RawClient::exchange(port, "GET /api/camera.jpg?t=99999999999999999 HTTP/1.1", "",
                                               "Host: 127.0.0.1\r\nRange: bytes=100000-200000\r\n");
  EXPECT_THAT(past, HasSubstr("HTTP/1.1 200"));
  EXPECT_EQ(body_size(past), body_size(jpeg));
  EXPECT_THAT(past, HasSubstr("Accept-Ranges: none"));
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
}

TEST_F(ViewerBinary, AForeignHostIsRefusedAndEveryAddressItServesOnIsPrinted) {
  const std::string frame = "GET /api/camera.jpg?t=99999999999999999 HTTP/1.1";
  {
    Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", sim_log_});
    const int port = start_viewer(viewer);
    ASSERT_GT(port, 0);
    // A page of another site whose name resolves to 127.0.0.1 (DNS rebinding) reads nothing.
    for (const std::string& host : std::vector<std::string>{"attacker.example", "attacker.example:" + std::to_string(port),
                                                            "127.0.0.1.attacker.example", "localhost.attacker.example", "10.1.2.4"}) {
      for (const std::string& request : {frame, std::string("GET / HTTP/1.1"), std::string("GET /api/snapshot HTTP/1.1")}) {
        const std::string answer = RawClient::exchange(port, request, "", "Host: " + host + "\r\n");
        EXPECT_THAT(answer, HasSubstr("HTTP/1.1 403")) << host << " " << request;
        EXPECT_THAT(answer, Not(HasSubstr("image/jpeg"))) << host;
      }
    }
    EXPECT_THAT(RawClient::exchange(port, frame, "", ""), HasSubstr("HTTP/1.1 400")) << "HTTP/1.1 without a Host";
    // The names it serves on, with any port (an ssh tunnel may forward another).
    for (const std::string& host : std::vector<std::string>{"127.0.0.1", "127.0.0.1:" + std::to_string(port), "localhost:9000", "LOCALHOST"}) {
      EXPECT_THAT(RawClient::exchange(port, frame, "", "Host: " + host + "\r\n"), HasSubstr("HTTP/1.1 200")) << host;
    }
    EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
  }
  // --allow-host adds names and addresses, and only those.
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", sim_log_, "--allow-host", "robot.example",
                     "--allow-host", "10.1.2.3"});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);
  for (const std::string host : {"robot.example", "robot.example:8080", "10.1.2.3"}) {
    EXPECT_THAT(RawClient::exchange(port, frame, "", "Host: " + host + "\r\n"), HasSubstr("HTTP/1.1 200")) << host;
  }
  EXPECT_THAT(RawClient::exchange(port, frame, "", "Host: 10.1.2.4\r\n"), HasSubstr("HTTP/1.1 403"));
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();

  // Every address: the URLs printed are real ones, never http://0:PORT/.
  Subprocess any({kViewer, "--listen", "0:0", "--log", sim_log_});
  const int any_port = start_viewer(any);
  ASSERT_GT(any_port, 0);
  EXPECT_THAT(any.output(), Not(HasSubstr("http://0:"))) << any.output();
  EXPECT_THAT(any.output(), Not(HasSubstr("http://0.0.0.0:"))) << any.output();
  EXPECT_THAT(RawClient::exchange(any_port, frame, "", "Host: 127.0.0.1\r\n"), HasSubstr("HTTP/1.1 200"));
  EXPECT_THAT(RawClient::exchange(any_port, frame, "", "Host: attacker.example\r\n"), HasSubstr("HTTP/1.1 403"));
  EXPECT_EQ(any.stop(10, SIGTERM), 0) << any.output();
}

TEST_F(ViewerBinary, ALogThatGetsShorterWhileServedIsAnErrorOnThePageNotACrash) {
  // The ordinary workflow: a log served, then a replay written into the same file.
  const std::string served = (dir_ / "served.lcmlog").string();
  fs::copy_file(sim_log_, served, fs::copy_options::overwrite_existing);
  Subprocess viewer({kViewer, "--listen", "127.0.0.1:0", "--log", served});
  const int port = start_viewer(viewer);
  ASSERT_GT(port, 0);
  const json status = get_json(port, "/status");
  const int64_t start = status["log"]["start"], end = status["log"]["end"];
  ASSERT_TRUE(get_json(port, "/api/snapshot?t=" + std::to_string(end))["camera"].is_object());
  {
    Subprocess replay({SLAMD_EXE, "--replay", sim_log_, "--output", served, "--config", kConfig});
    ASSERT_EQ(replay.wait(120), 0) << replay.output();
  }
  ASSERT_LT(fs::file_size(served), fs::file_size(sim_log_) / 10);
  // Back to the start (every message read again) and the camera frame: an error saying why.
  for (const std::string& path : std::vector<std::string>{"/api/snapshot?t=" + std::to_string(start),
                                                          "/api/camera.jpg?t=" + std::to_string(start), "/api/snapshot"}) {
    const std::string answer = RawClient::exchange(port, "GET " + path + " HTTP/1.1");
    EXPECT_THAT(answer, HasSubstr("HTTP/1.1 503")) << path;
    EXPECT_THAT(answer, HasSubstr("got shorter under the viewer")) << path;
  }
  const json after = get_json(port, "/status");
  ASSERT_TRUE(after.is_object()) << "the viewer is still serving";
  EXPECT_THAT(after["log"]["error"].get<std::string>(), HasSubstr("served.lcmlog got shorter"));
  // The page says so.
  const std::string dom = chromium({"--dump-dom"}, "http://127.0.0.1:" + std::to_string(port) + "/");
  EXPECT_THAT(element_text(dom, "connection"), HasSubstr("got shorter under the viewer")) << dom.substr(0, 2000);
  EXPECT_EQ(viewer.stop(10, SIGTERM), 0) << viewer.output();
}

TEST(ViewerCommandLine, UsageErrorsExitTwoWithOneLine) {
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--listen", "nonsense"}, {"--listen", "127.0.0.1:99999"}, {"--bogus"}, {"--log", "/nonexistent.lcmlog"},
           {"--max-clients", "0"}, {"--log", WHISKEYE_SOURCE_DIR "/README.md", "--lcm-url", "udpm://239.255.76.67:7667"}}) {
    std::vector<std::string> argv{kViewer};
    argv.insert(argv.end(), args.begin(), args.end());
    Subprocess p(argv);
    EXPECT_EQ(p.wait(10), 2) << args[0] << "\n" << p.output();
    const std::string out = p.output();
    EXPECT_EQ(out.rfind("whiskeye-viewer: ", 0), 0u) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  }
  Subprocess help({kViewer, "--help"});
  EXPECT_EQ(help.wait(10), 0);
  EXPECT_THAT(help.output(), HasSubstr("--listen"));
  // A file that is no LCM log is refused with exit 1, naming it.
  Subprocess notlog({kViewer, "--listen", "127.0.0.1:0", "--log", WHISKEYE_SOURCE_DIR "/README.md"});
  EXPECT_EQ(notlog.wait(10), 1) << notlog.output();
  EXPECT_THAT(notlog.output(), HasSubstr("README.md"));
}

}  // namespace
}  // namespace whiskeye
