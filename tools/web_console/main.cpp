// rover_web: the live web console (./rover console --web). One process on the bus (a
// bus::Process: validated messages, a heartbeat, --key signing) and an HTTP server
// (cpp-httplib) on 127.0.0.1 by default:
//
//   GET  /                 the page (static/index.html, static/app.js, embedded at build time)
//   GET  /api/state        the whole picture, one JSON object (web_state.hpp); in playback
//                          ?at=SECONDS picks the log time (else where the playback is)
//   GET  /api/events       the same as Server-Sent Events, twice a second
//   GET  /api/image.png    the newest NAVCAM left image, reduced (?width=N, 32 to 1024; in
//                          playback ?at=SECONDS as for /api/state)
//   POST /api/submit       body: a sequence's text (?name=NAME); checked here first (400 with
//                          the checker's line), then published on SEQUENCE_SUBMIT
//   POST /api/pause, /api/resume, /api/abort   body: an optional one-line reason
//
// A command is answered once the executor has said what became of it (command_watch.hpp,
// as rover_seq finds out): 200 when it took it (a submit: its first status), 403 with the
// executor's reason when it dropped it (unsigned on a signed stack, a wrong key), 409 when
// it rejected the sequence, 504 when it said nothing within kAnswerWaitS. A console whose
// commands the stack will refuse (no key on a signed stack, a key that does not verify
// its messages) says so once on stderr and in the page's state (commands.key_problem).
//
// Every POST needs the operator secret in the X-Rover-Secret header (403 otherwise), and
// is signed with the deployment's key when one is held (--key, auth.key_file,
// $ROVER_KEY_FILE), through the same Bus signing as every process and rover_seq.
// Requests whose Host header is not this console's (DNS rebinding) are refused.
//
// --listen unix:PATH serves on a Unix socket instead (mode 0600): the way out of a private
// network namespace, whose loopback no browser outside can reach, since the file system
// is shared. `./rover console --web --private NAME` runs it so inside the named private
// bus and forwards this computer's 127.0.0.1:PORT to it with socat.
//
// With --log FILE it plays back a recorded log instead (log_playback.hpp): the same state,
// the page gets a time slider, no bus is joined (memq://, unless --lcm-url says otherwise)
// and every command is refused.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "auth/auth.hpp"
#include "bus/process.hpp"
#include "config/file_read.hpp"
#include "config/yaml_config.hpp"
#include "report/json_writer.hpp"
#include "sequence/parser.hpp"
#include "web_console/command_watch.hpp"
#include "web_console/log_playback.hpp"
#include "web_console/static_files.hpp"
#include "web_console/web_state.hpp"

#include <httplib.h>

#include <rover_msgs/sequence_control_t.hpp>

#include <arpa/inet.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <future>
#include <iostream>
#include <memory>
#include <mutex>
#include <thread>

using rover::config::ConfigError;

namespace {

constexpr const char* kSecretHeader = "X-Rover-Secret";
constexpr std::size_t kMaxReasonBytes = 200;
constexpr std::size_t kMinSecretBytes = 12;
// How long a command waits for the executor to say what became of it (rover_seq: 4 s).
constexpr double kAnswerWaitS = 5.0;

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Listen {
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string unix_path;  // --listen unix:PATH; host and port unused
};

int ParsePort(const std::string& text, const std::string& flag) {
  try {
    std::size_t used = 0;
    const long v = std::stol(text, &used);
    if (used == text.size() && v >= 0 && v <= 65535) return static_cast<int>(v);
  } catch (const std::exception&) {
  }
  throw ConfigError("rover_web: argument " + flag + ": \"" + text + "\": expected a port number, 0 to 65535 (0: any free port)");
}

Listen ParseListen(const std::string& text) {
  if (text.rfind("unix:", 0) == 0) {
    Listen l;
    l.unix_path = text.substr(5);
    sockaddr_un addr{};
    if (l.unix_path.empty() || l.unix_path.size() >= sizeof(addr.sun_path)) {
      throw ConfigError("rover_web: argument --listen: \"" + text + "\": expected unix:PATH with a path of 1 to " +
                        std::to_string(sizeof(addr.sun_path) - 1) + " characters");
    }
    return l;
  }
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) {
    throw ConfigError("rover_web: argument --listen: \"" + text + "\": expected ADDR:PORT (e.g. 127.0.0.1:8080) or unix:PATH");
  }
  Listen l;
  l.host = text.substr(0, colon);
  if (l.host == "localhost") l.host = "127.0.0.1";
  in_addr addr{};
  if (inet_pton(AF_INET, l.host.c_str(), &addr) != 1) {
    throw ConfigError("rover_web: argument --listen: \"" + text + "\": expected an IPv4 address (such as 127.0.0.1) before the colon");
  }
  l.port = ParsePort(text.substr(colon + 1), "--listen");
  return l;
}

bool IsLoopback(const std::string& host) { return host.rfind("127.", 0) == 0; }

// A Host header naming this computer's loopback, with any port or none: what a browser
// sends through a forwarder (socat) to a console on a Unix socket, whose port the console
// cannot know. Another site's name (DNS rebinding) is not one.
bool IsLoopbackHostHeader(const std::string& host) {
  for (const char* name : {"127.0.0.1", "localhost", "[::1]"}) {
    const std::size_t n = std::strlen(name);
    if (host.compare(0, n, name) != 0) continue;
    if (host.size() == n) return true;
    if (host[n] != ':' || host.size() == n + 1) return false;
    return std::all_of(host.begin() + static_cast<std::ptrdiff_t>(n) + 1, host.end(),
                       [](char c) { return c >= '0' && c <= '9'; });
  }
  return false;
}

// Ready to bind a Unix socket at `path`: a socket left by a console that died is removed;
// one that answers, or a file that is not a socket, is an error.
void ClearStaleSocket(const std::string& path) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0) return;
  const std::string where = "rover_web: argument --listen: unix:" + path + ": ";
  if (!S_ISSOCK(st.st_mode)) throw ConfigError(where + "exists and is not a socket (expected a free path)");
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof(addr.sun_path) - 1);
  const bool answers = fd >= 0 && connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0;
  if (fd >= 0) close(fd);
  if (answers) throw ConfigError(where + "another console listens there (expected a free path)");
  if (unlink(path.c_str()) != 0) throw ConfigError(where + "a stale socket that cannot be removed: " + std::strerror(errno));
}

// The operator secret from --secret-file (a regular file no other user can read) or
// --secret; "" when neither is given (commands are then refused).
std::string LoadSecret(const std::optional<std::string>& file, const std::optional<std::string>& literal) {
  if (file && literal) throw ConfigError("rover_web: --secret and --secret-file: expected one of them, not both");
  std::string secret;
  std::string where;
  if (file) {
    where = "rover_web: argument --secret-file: " + *file + ": ";
    try {
      secret = rover::config::ReadBoundedRegularFile(*file, 4096, "secret file");
    } catch (const std::exception& e) {
      throw ConfigError(std::string("rover_web: argument --secret-file: ") + e.what());
    }
    struct stat st {};
    if (stat(file->c_str(), &st) == 0 && (st.st_mode & S_IRWXO) != 0) {
      throw ConfigError(where + "other users can read it (expected mode 0600 or 0640: chmod o-rwx)");
    }
    while (!secret.empty() && (secret.back() == '\n' || secret.back() == '\r' || secret.back() == ' '))
      secret.pop_back();
  } else if (literal) {
    where = "rover_web: argument --secret: ";
    secret = *literal;
  } else {
    return "";
  }
  if (secret.size() < kMinSecretBytes) {
    throw ConfigError(where + "the secret is " + std::to_string(secret.size()) + " characters (expected at least " +
                      std::to_string(kMinSecretBytes) + ")");
  }
  for (unsigned char c : secret) {
    if (c < 0x21 || c > 0x7e) throw ConfigError(where + "expected printable ASCII without spaces (it goes in an HTTP header)");
  }
  return secret;
}

// Compares in time independent of where the strings differ.
bool SameSecret(const std::string& a, const std::string& b) {
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? a[i] : 0, y = i < b.size() ? b[i] : 0;
    diff |= static_cast<unsigned>(x ^ y);
  }
  return diff == 0;
}

// A command from a page, published by the bus thread (the Bus is not thread-safe).
struct Pending {
  enum Kind { kSubmit, kControl } kind = kSubmit;
  rover_msgs::sequence_submit_t submit{};
  rover_msgs::sequence_control_t control{};
  std::promise<std::string> done;  // "" or why publishing failed
};

class CommandQueue {
 public:
  std::future<std::string> Push(std::shared_ptr<Pending> p) {
    auto f = p->done.get_future();
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(p));
    return f;
  }
  std::deque<std::shared_ptr<Pending>> Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::deque<std::shared_ptr<Pending>> out;
    out.swap(queue_);
    return out;
  }

 private:
  std::mutex mutex_;
  std::deque<std::shared_ptr<Pending>> queue_;
};

void Text(httplib::Response& res, int status, const std::string& line) {
  res.status = status;
  res.set_content(line + "\n", "text/plain; charset=utf-8");
}

// A one-line reason from a page: printable, at most kMaxReasonBytes.
std::string CheckReason(const std::string& body, std::string* reason) {
  std::string r = body;
  while (!r.empty() && (r.back() == '\n' || r.back() == '\r')) r.pop_back();
  if (r.size() > kMaxReasonBytes) return "reason: " + std::to_string(r.size()) + " bytes (expected at most " + std::to_string(kMaxReasonBytes) + ")";
  for (unsigned char c : r) {
    if (c < 0x20 || c == 0x7f) return "reason: a control character (expected one line of text)";
  }
  *reason = r;
  return "";
}

// A playback joins no bus: LCM's in-process transport, unless --lcm-url names one.
std::vector<char*> PlaybackArguments(int argc, char** argv) {
  std::vector<char*> args(argv, argv + argc);
  bool log = false, url = false;
  for (int i = 1; i < argc; ++i) {
    log = log || std::strcmp(argv[i], "--log") == 0;
    url = url || std::strcmp(argv[i], "--lcm-url") == 0;
  }
  static char flag[] = "--lcm-url", memq[] = "memq://";
  if (log && !url) {
    args.push_back(flag);
    args.push_back(memq);
  }
  return args;
}

// ?at=SECONDS (log time) in a playback request; none: where the playback is.
std::optional<std::int64_t> RequestedTime(const httplib::Request& req, std::string* bad) {
  if (!req.has_param("at")) return std::nullopt;
  const std::string text = req.get_param_value("at");
  try {
    std::size_t used = 0;
    const double s = std::stod(text, &used);
    // Far outside any log clamps to its ends anyway; the bound keeps the microseconds in range.
    if (used == text.size() && std::isfinite(s)) return std::llround(std::clamp(s, -9.0e12, 9.0e12) * 1e6);
  } catch (const std::exception&) {
  }
  *bad = "at: \"" + text + "\": expected a log time in seconds (the state's playback.first_s to last_s)";
  return std::nullopt;
}

// The console's command line.
struct ConsoleArgs {
  Listen listen;
  int image_width = 256;
  std::string secret;                   // "": commands off
  std::optional<std::string> log_path;  // playback
};

ConsoleArgs ParseConsoleArgs(const rover::bus::Process& proc) {
  ConsoleArgs a;
  if (auto l = proc.option("--listen")) a.listen = ParseListen(*l);
  if (auto p = proc.option("--port")) {
    if (proc.option("--listen")) throw ConfigError("rover_web: --port and --listen: expected one of them, not both");
    a.listen.port = ParsePort(*p, "--port");
  }
  if (auto w = proc.option("--image-width")) {
    a.image_width = ParsePort(*w, "--image-width");
    if (a.image_width < 32 || a.image_width > 1024) {
      throw ConfigError("rover_web: argument --image-width: \"" + *w + "\": expected 32 to 1024");
    }
  }
  a.secret = LoadSecret(proc.option("--secret-file"), proc.option("--secret"));
  a.log_path = proc.option("--log");
  if (a.log_path && !a.secret.empty()) {
    throw ConfigError("rover_web: --log and an operator secret: a playback sends no commands (expected one of them)");
  }
  return a;
}

// The recorded log to play back, with one line on what it holds.
std::unique_ptr<rover::web::LogPlayback> OpenPlayback(const std::string& log_path,
                                                      const rover::web::WebStateOptions& options) {
  std::unique_ptr<rover::web::LogPlayback> playback;
  try {
    playback = std::make_unique<rover::web::LogPlayback>(log_path, options);
  } catch (const std::runtime_error& e) {
    throw ConfigError(std::string("rover_web: argument --log: ") + e.what());
  }
  char span[96];
  std::snprintf(span, sizeof(span), "log time %.3f to %.3f s (%.1f s)", playback->first_utime() * 1e-6,
                playback->last_utime() * 1e-6, (playback->last_utime() - playback->first_utime()) * 1e-6);
  std::cout << "rover_web: playing back " << log_path << ": " << playback->messages() << " messages, " << span
            << (playback->rejected() > 0 ? ", " + std::to_string(playback->rejected()) +
                                               " left out (they do not decode or fail the bus's checks)"
                                         : std::string())
            << "\n" << std::flush;
  return playback;
}

// What the page shows, from the bus. Rover time: the Process keeps the clock (ROVER_CLOCK,
// checked and, with a key, its signature verified once); each tick hands its newest time
// to the state. A second subscription to ROVER_CLOCK here would verify each signed clock
// message twice, and the second time drop it as a replay.
void FeedStateFromBus(rover::bus::Bus& bus, rover::web::WebState& state) {
  namespace ch = rover::channels;
  auto feed = [&state](const auto& m) { state.On(m, Now()); };
  bus.Subscribe<rover_msgs::pose_t>(ch::kPose, feed, 100);
  bus.Subscribe<rover_msgs::sim_truth_t>(ch::kSimTruth, feed, 100);
  bus.Subscribe<rover_msgs::traversability_map_t>(ch::kTraversabilityMap, feed, 10);
  bus.Subscribe<rover_msgs::keepout_zones_t>(ch::kKeepOutZones, feed, 10);
  bus.Subscribe<rover_msgs::sequence_status_t>(ch::kSequenceStatus, feed, 50);
  bus.Subscribe<rover_msgs::sequence_submit_t>(ch::kSequenceSubmit, feed, 10);
  bus.Subscribe<rover_msgs::step_report_t>(ch::kStepReport, feed, 50);
  bus.Subscribe<rover_msgs::vo_update_t>(ch::kVoUpdate, feed, 50);
  bus.Subscribe<rover_msgs::hazard_status_t>(ch::kHazardStatus, feed, 50);
  bus.Subscribe<rover_msgs::heartbeat_t>(ch::kHeartbeat, feed, 100);
  bus.Subscribe<rover_msgs::stereo_frame_t>(ch::kStereoFrame, feed, 4);
}

// The HTTP side: the page, the state, the image and the commands, over the live state or
// a playback.
class WebConsole {
 public:
  WebConsole(rover::bus::Process& proc, ConsoleArgs args, rover::web::WebStateOptions options)
      : proc_(proc), args_(std::move(args)), options_(options), state_(options_),
        watch_(options_.signing, "sequence_executor", options_.signing ? rover::auth::InstanceName(proc.name()) : "") {
    if (args_.log_path) playback_ = OpenPlayback(*args_.log_path, options_);
    FeedStateFromBus(proc_.bus(), state_);
    if (!playback_) WatchCommands();
    server_.set_payload_max_length(rover::config::kMaxSequenceFileBytes);  // larger: 413
    server_.set_read_timeout(5, 0);
    server_.set_write_timeout(5, 0);
    server_.set_keep_alive_timeout(1);
    RefuseOtherHosts();
    ExplainRefusals();
    ServePages();
    TakeCommands();
  }

  int Run() {
    const int port = Bind();
    std::thread http([&] { server_.listen_after_bind(); });
    Announce(port);
    if (playback_) {
      // Nothing to hear or send: serve until SIGINT or SIGTERM.
      while (!proc_.stopping()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    } else {
      proc_.Run([&] { PublishPendingCommands(); }, 20);
    }
    stopping_ = true;
    server_.stop();
    http.join();
    if (!args_.listen.unix_path.empty()) unlink(args_.listen.unix_path.c_str());
    for (auto& p : commands_.Take()) p->done.set_value("rover_web is stopping");
    return 0;
  }

 private:
  // What the executor says of the commands sent (command_watch.hpp). Its heartbeat is read
  // unverified: with a key that does not verify the stack's messages, the Bus would drop
  // the very heartbeat that says why the commands are refused.
  void WatchCommands() {
    namespace ch = rover::channels;
    proc_.bus().SubscribeUnverified<rover_msgs::heartbeat_t>(
        ch::kHeartbeat, [this](const rover_msgs::heartbeat_t& hb) { watch_.OnHeartbeat(hb); }, 100);
    proc_.bus().Subscribe<rover_msgs::sequence_status_t>(
        ch::kSequenceStatus, [this](const rover_msgs::sequence_status_t& st) { watch_.OnStatus(st); }, 50);
  }

  // On the bus thread: what the console's own bus refused for its authentication, and a
  // key problem said once, on stderr and on the page.
  void CheckKey() {
    const rover::bus::Bus& bus = proc_.bus();
    if (bus.auth_rejected() > auth_rejected_seen_) {
      auth_rejected_seen_ = bus.auth_rejected();
      watch_.OnAuthRejection(bus.last_auth_rejection());
    }
    if (const std::string problem = watch_.TakeNewKeyProblem(); !problem.empty()) {
      std::cerr << "rover_web: " << problem << "\n" << std::flush;
      state_.SetKeyProblem(problem);
    }
  }

  // The answer to a command (`what`, for the log) from what the executor said, or did not
  // say, of it; a command not taken is logged with the same line the page shows.
  static void Answer(const rover::web::CommandWatch::Verdict& v, const std::string& what,
                     const std::string& accepted_json, httplib::Response& res) {
    using V = rover::web::CommandWatch::Verdict;
    if (v.kind == V::kAccepted) return res.set_content(accepted_json, "application/json");
    const int status = v.kind == V::kRefused ? 403 : v.kind == V::kRejected ? 409 : 504;
    const std::string line = v.kind == V::kRefused    ? "refused by sequence_executor: " + v.text
                             : v.kind == V::kRejected ? "rejected by sequence_executor: " + v.text
                                                      : "sent, but " + v.text;
    std::cout << "rover_web: " << what << ": " << line << "\n" << std::flush;
    Text(res, status, line);
  }

  // A page from another site that a DNS name re-pointed at 127.0.0.1 sends its own name in
  // Host: refuse it, so no other site can read the bus through the browser.
  void RefuseOtherHosts() {
    server_.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      const Listen& listen = args_.listen;
      if (!listen.unix_path.empty() || IsLoopback(listen.host)) {
        const std::string host = req.get_header_value("Host");
        const bool allowed = listen.unix_path.empty()
                                 ? std::find(allowed_hosts_.begin(), allowed_hosts_.end(), host) != allowed_hosts_.end()
                                 : IsLoopbackHostHeader(host);
        if (!allowed) {
          Text(res, 403, "refused: Host \"" + host + "\" is not this console (expected 127.0.0.1 or localhost with its port)");
          return httplib::Server::HandlerResponse::Handled;
        }
      }
      res.set_header("Cache-Control", "no-store");
      res.set_header("X-Content-Type-Options", "nosniff");
      res.set_header("X-Frame-Options", "DENY");
      return httplib::Server::HandlerResponse::Unhandled;
    });
  }

  // httplib's own refusals (no route, no Content-Length, too large) get a line too.
  void ExplainRefusals() {
    server_.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
      if (!res.body.empty()) return;
      std::string line = "HTTP " + std::to_string(res.status);
      if (res.status == 404) {
        line = "not found: " + req.path + " (expected /, /api/state, /api/events, /api/image.png, or a POST to "
               "/api/submit, /api/pause, /api/resume, /api/abort)";
      } else if (res.status == 413) {
        line = "request too large (a sequence is at most " + std::to_string(rover::config::kMaxSequenceFileBytes) + " bytes)";
      } else if (res.status == 400) {
        line = "bad request (a POST needs a Content-Length header and a body, which may be empty)";
      }
      Text(res, res.status, line);
    });
  }

  // The picture a request asks for: the live state, or the playback's at ?at= (else where
  // it is). "" with `bad` set for a bad ?at=.
  std::string StateJson(const httplib::Request& req, std::string* bad) {
    if (!playback_) return state_.StateJson(Now());
    const auto at = RequestedTime(req, bad);
    return bad->empty() ? playback_->StateJsonAt(at) : "";
  }

  void ServePages() {
    server_.Get("/", [this](const httplib::Request& req, httplib::Response& res) { Page(req, res); });
    server_.Get("/app.js", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(rover::web::kAppJs, "text/javascript; charset=utf-8");
    });
    server_.Get("/api/state", [this](const httplib::Request& req, httplib::Response& res) {
      std::string bad;
      std::string json = StateJson(req, &bad);
      if (!bad.empty()) return Text(res, 400, bad);
      res.set_content(json, "application/json");
    });
    server_.Get("/api/events", [this](const httplib::Request&, httplib::Response& res) {
      res.set_chunked_content_provider("text/event-stream", [this](std::size_t, httplib::DataSink& sink) {
        // In playback: where the playback is (the page asks /api/state?at= itself).
        const std::string event =
            "data: " + (playback_ ? playback_->StateJsonAt(std::nullopt) : state_.StateJson(Now())) + "\n\n";
        if (!sink.write(event.data(), event.size())) return false;
        for (int i = 0; i < 10 && !stopping_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        if (stopping_) sink.done();
        return true;
      });
    });
    server_.Get("/api/image.png", [this](const httplib::Request& req, httplib::Response& res) { Image(req, res); });
  }

  // The page carries the state it was served with (in a JSON data block, which no browser
  // runs), so its first picture needs no round trip. '<' never appears in JSON outside
  // strings, and as \u003c no string can close the block.
  void Page(const httplib::Request& req, httplib::Response& res) {
    std::string bad;
    std::string json = StateJson(req, &bad);
    if (!bad.empty()) return Text(res, 400, bad);
    std::string escaped;
    escaped.reserve(json.size());
    for (char c : json) escaped += c == '<' ? std::string("\\u003c") : std::string(1, c);
    std::string html = rover::web::kIndexHtml;
    if (const auto at = html.find("{{STATE}}"); at != std::string::npos) html.replace(at, 9, escaped);
    res.set_header("Content-Security-Policy",
                   "default-src 'none'; script-src 'self'; connect-src 'self'; img-src 'self'; "
                   "style-src 'unsafe-inline'; frame-ancestors 'none'");
    res.set_content(html, "text/html; charset=utf-8");
  }

  void Image(const httplib::Request& req, httplib::Response& res) {
    int width = args_.image_width;
    if (req.has_param("width")) {
      try {
        width = ParsePort(req.get_param_value("width"), "width");
      } catch (const ConfigError&) {
        width = -1;
      }
      if (width < 32 || width > 1024) return Text(res, 400, "width: expected a number of pixels, 32 to 1024");
    }
    std::string why;
    if (playback_) {
      const auto at = RequestedTime(req, &why);
      if (!why.empty()) return Text(res, 400, why);
      std::string png = playback_->LeftImagePngAt(at, width, &why);
      if (png.empty()) return Text(res, 404, why);
      return res.set_content(png, "image/png");
    }
    std::string png = state_.LeftImagePng(width, &why);
    if (png.empty()) return Text(res, 404, why);
    res.set_content(png, "image/png");
  }

  // Commands: the secret, then the input, then the bus thread publishes (and signs).
  void TakeCommands() {
    server_.Post("/api/submit", [this](const httplib::Request& req, httplib::Response& res) { Submit(req, res); });
    Control("/api/pause", rover_msgs::sequence_control_t::ACTION_PAUSE, "pause");
    Control("/api/resume", rover_msgs::sequence_control_t::ACTION_RESUME, "resume");
    Control("/api/abort", rover_msgs::sequence_control_t::ACTION_ABORT, "abort");
  }

  bool Authorised(const httplib::Request& req, httplib::Response& res) {
    if (playback_) {
      Text(res, 403, "refused: rover_web is playing back " + playback_->path() + ", not on a bus: commands are off");
      return false;
    }
    if (args_.secret.empty()) {
      Text(res, 403, "refused: rover_web was started without --secret-file or --secret, so commands are off");
      return false;
    }
    if (!req.has_header(kSecretHeader)) {
      Text(res, 403, std::string("refused: this command needs the operator secret (header ") + kSecretHeader + ")");
      return false;
    }
    if (!SameSecret(req.get_header_value(kSecretHeader), args_.secret)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(250));  // slows guessing
      Text(res, 403, "refused: wrong operator secret");
      std::cerr << "rover_web: refused a command from " << req.remote_addr << ": wrong operator secret\n";
      return false;
    }
    return true;
  }

  // Hands a command to the bus thread and waits for it to be published.
  bool Publish(std::shared_ptr<Pending> p, httplib::Response& res) {
    auto done = commands_.Push(p);
    if (done.wait_for(std::chrono::seconds(3)) != std::future_status::ready) {
      Text(res, 503, "the bus did not take the command within 3 s (rover_web is stopping or stalled)");
      return false;
    }
    if (std::string why = done.get(); !why.empty()) {
      Text(res, 500, "publishing failed: " + why);
      return false;
    }
    return true;
  }

  // Milliseconds since the epoch, strictly increasing even for two submits in one
  // millisecond.
  std::int64_t NextSubmissionId() {
    std::int64_t id = static_cast<std::int64_t>(
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count() * 1e3);
    std::int64_t prev = last_submission_.load();
    while (true) {
      const std::int64_t next = std::max(id, prev + 1);
      if (last_submission_.compare_exchange_weak(prev, next)) return next;
    }
  }

  void Submit(const httplib::Request& req, httplib::Response& res) {
    if (!Authorised(req, res)) return;
    std::string name = req.has_param("name") ? req.get_param_value("name") : "web";
    if (name.empty() || name.size() > 200) return Text(res, 400, "name: expected 1 to 200 characters");
    for (unsigned char c : name) {
      if (c < 0x20 || c == 0x7f) return Text(res, 400, "name: a control character (expected one line of text)");
    }
    if (req.body.empty()) return Text(res, 400, "empty body (expected the sequence's text)");
    const auto check = rover::sequence::ParseSequence(req.body, name);
    if (!check.ok()) return Text(res, 400, check.errors.front().ToString());
    auto p = std::make_shared<Pending>();
    p->kind = Pending::kSubmit;
    const std::int64_t id = NextSubmissionId();
    p->submit.submission_id = id;
    p->submit.name = name;
    p->submit.text = req.body;
    const auto ticket = watch_.Expect(rover::channels::kSequenceSubmit, id);
    if (!Publish(p, res)) return;
    std::cout << "rover_web: submitted " << name << " as " << id << (options_.signing ? " (signed)" : "") << " for "
              << req.remote_addr << "\n" << std::flush;
    const auto verdict = watch_.Wait(ticket, kAnswerWaitS);
    Answer(verdict, "submission " + std::to_string(id),
           "{\"submission_id\":" + std::to_string(id) + ",\"signed\":" + (options_.signing ? "true" : "false") +
               ",\"executor\":" + rover::tools::JsonWriter::Quote(verdict.text) + "}\n",
           res);
  }

  void Control(const char* path, std::int8_t action, const std::string& verb) {
    server_.Post(path, [this, action, verb](const httplib::Request& req, httplib::Response& res) {
      if (!Authorised(req, res)) return;
      std::string reason;
      if (std::string bad = CheckReason(req.body, &reason); !bad.empty()) return Text(res, 400, bad);
      auto p = std::make_shared<Pending>();
      p->kind = Pending::kControl;
      p->control.action = action;
      p->control.reason = reason.empty() ? "operator " + verb + " (web console)" : reason;
      const auto ticket = watch_.Expect(rover::channels::kSequenceControl);
      if (!Publish(p, res)) return;
      std::cout << "rover_web: " << verb << " sent" << (options_.signing ? " (signed)" : "") << ": "
                << p->control.reason << "\n" << std::flush;
      const auto verdict = watch_.Wait(ticket, kAnswerWaitS);
      Answer(verdict, verb,
             "{\"sent\":\"" + verb + "\",\"signed\":" + (options_.signing ? "true" : "false") +
                 ",\"executor\":" + rover::tools::JsonWriter::Quote(verdict.text) + "}\n",
             res);
    });
  }

  // On the bus thread (the Bus is not thread-safe): the rover time to the state, and the
  // pages' commands onto the bus.
  void PublishPendingCommands() {
    state_.OnRoverClock(proc_.now());
    CheckKey();
    for (auto& p : commands_.Take()) {
      try {
        if (p->kind == Pending::kSubmit) {
          proc_.bus().Publish(rover::channels::kSequenceSubmit, p->submit);
        } else {
          proc_.bus().Publish(rover::channels::kSequenceControl, p->control);
        }
        p->done.set_value("");
      } catch (const std::exception& e) {
        p->done.set_value(e.what());
      }
    }
  }

  // Binds the socket; the port (the one chosen for port 0). The Host names a request may
  // carry follow from it.
  int Bind() {
    const Listen& listen = args_.listen;
    int port = listen.port;
    if (!listen.unix_path.empty()) {
      ClearStaleSocket(listen.unix_path);
      server_.set_address_family(AF_UNIX);
      const mode_t old_mask = umask(0177);  // the socket is born 0600: only this user connects
      const bool bound = server_.bind_to_port(listen.unix_path, 80);
      umask(old_mask);
      if (!bound) {
        throw ConfigError("rover_web: cannot listen on unix:" + listen.unix_path + ": " + std::strerror(errno) +
                          " (expected a path in a directory this user can write)");
      }
    } else if (port == 0) {
      port = server_.bind_to_any_port(listen.host);
      if (port < 0) throw std::runtime_error("cannot listen on " + listen.host + " (any port)");
    } else if (!server_.bind_to_port(listen.host, port)) {
      throw ConfigError("rover_web: cannot listen on " + listen.host + ":" + std::to_string(port) +
                        " (in use, or not an address of this host; choose another with --port or --listen)");
    }
    for (const std::string& h : {std::string("127.0.0.1"), std::string("localhost"), std::string("[::1]"), listen.host}) {
      allowed_hosts_.push_back(h + ":" + std::to_string(port));
      if (port == 80) allowed_hosts_.push_back(h);  // browsers leave the default port out
    }
    return port;
  }

  void Announce(int port) const {
    const Listen& listen = args_.listen;
    const std::string where = listen.unix_path.empty() ? "http://" + listen.host + ":" + std::to_string(port) + "/"
                                                       : "unix:" + listen.unix_path;
    if (playback_) {
      std::cout << "rover_web: listening on " << where << " (playback of " << *args_.log_path << "; commands off)\n"
                << std::flush;
    } else {
      std::cout << "rover_web: listening on " << where << " (bus " << proc_.bus().url() << "; commands "
                << (args_.secret.empty() ? "off: no operator secret" : "need the operator secret")
                << (options_.signing ? ", signed with the deployment's key" : ", unsigned (no key)") << ")\n"
                << std::flush;
    }
    if (listen.unix_path.empty() && !IsLoopback(listen.host)) {
      std::cout << "rover_web: warning: listening on " << listen.host
                << ", not loopback: anyone who reaches this port reads the bus (plain HTTP, no TLS)\n";
    }
  }

  rover::bus::Process& proc_;
  const ConsoleArgs args_;
  const rover::web::WebStateOptions options_;
  rover::web::WebState state_;
  rover::web::CommandWatch watch_;
  std::int64_t auth_rejected_seen_ = 0;
  std::unique_ptr<rover::web::LogPlayback> playback_;
  httplib::Server server_;
  std::vector<std::string> allowed_hosts_;  // filled once the port is known
  CommandQueue commands_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::int64_t> last_submission_{0};
};

}  // namespace

int main(int argc_in, char** argv_in) {
  std::vector<char*> arguments = PlaybackArguments(argc_in, argv_in);
  const int argc = static_cast<int>(arguments.size());
  char** argv = arguments.data();
  return rover::bus::RunMain("rover_web", [&]() -> int {
    rover::bus::Process proc(
        "rover_web",
        "The live web console: the traverse on the traversability map, keep-out zones, the goal\n"
        "of a goto, the estimate with its 3-sigma ellipse, truth in simulation, the step table,\n"
        "VO, hazards, every process's heartbeat, the sequence and its current line, and the\n"
        "newest NAVCAM left image. Open http://ADDR:PORT/ in a browser.\n"
        "Commands (submit, pause, resume, abort) need the operator secret (--secret-file or\n"
        "--secret; the page asks for it and sends it in the X-Rover-Secret header); without one\n"
        "the console is read-only. With the deployment's key (--key) they are signed.\n"
        "Listens on 127.0.0.1 unless told otherwise: anyone who can reach the port sees the bus.\n"
        "With --log FILE it plays back a recorded LCM log instead (rover_recorder, ./rover scenario\n"
        "--out): the same page with a time slider; no bus is joined and commands are refused.",
        argc, argv,
        {{"--listen", "ADDR:PORT|unix:PATH",
          "where to listen (default 127.0.0.1:8080; port 0: any free port; unix:PATH a Unix socket, mode 0600)"},
         {"--port", "P", "the port on 127.0.0.1 (short for --listen 127.0.0.1:P)"},
         {"--secret-file", "FILE", "the operator secret for commands: a file no other user can read"},
         {"--secret", "TOKEN", "the operator secret on the command line (other local users may see it in ps)"},
         {"--image-width", "PX", "width of the NAVCAM image served (default 256, 32 to 1024)"},
         {"--log", "FILE", "play back this LCM log instead of showing the live bus (commands off)"}});

    // Started by hand on a running simulation, the console is outside its barrier and runs
    // in real time: it follows the virtual clock as an observer rather than dropping it and
    // then every message stamped with it. (The tests start it inside the barrier.)
    proc.set_clock_observer(true);
    ConsoleArgs args = ParseConsoleArgs(proc);
    rover::web::WebStateOptions options;
    options.bus_url = args.log_path ? "" : proc.bus().url();
    options.commands_enabled = !args.secret.empty();
    options.signing = !args.log_path && proc.bus().has_auth();
    WebConsole console(proc, std::move(args), options);
    proc.DeclarePublications({{rover::channels::kSequenceSubmit, "commands are on (--secret-file, --secret)"},
                              {rover::channels::kSequenceControl, "commands are on (--secret-file, --secret)"}});
    return console.Run();
  });
}
