#include "view/server.h"

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <list>
#include <mutex>
#include <optional>
#include <random>
#include <string_view>
#include <thread>

#include "core/check.h"
#include "core/text_format.h"
#include "io/image/jpeg_io.h"
#include "io/image/png_io.h"
#include "view/web_assets.h"

namespace candi::view {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

constexpr size_t kHeaderLimit = 8192, kTargetLimit = 2048, kBodyLimit = 1024;
// A connection has kUnauthorisedSeconds to send a request with the token, then kIdleSeconds
// between requests.
constexpr int kUnauthorisedSeconds = 5, kIdleSeconds = 30;
// Replies a page has not read: at most this many (or bytes), else the page is closed.
constexpr size_t kMaxQueuedTexts = 16, kMaxQueuedTextBytes = size_t{64} << 20;
constexpr std::chrono::milliseconds kAcceptPause(100);

std::string RandomToken() {
  std::random_device device;  // /dev/urandom
  std::string hex;
  static const char* digits = "0123456789abcdef";
  for (int i = 0; i < 4; ++i) {
    const uint32_t word = device();
    for (int k = 0; k < 8; ++k) hex += digits[(word >> (4 * k)) & 15];
  }
  return hex;
}

bool ConstantTimeEqual(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsLoopback(const std::string& bind) { return bind == "127.0.0.1" || bind == "localhost" || bind == "::1"; }

bool IsIpLiteral(const std::string& host) {
  boost::system::error_code ec;
  net::ip::make_address(host, ec);
  return !ec;
}

// "host:port" or "[v6]:port" -> host (brackets removed) and port text.
bool SplitHostPort(const std::string& text, std::string* host, std::string* port) {
  if (!text.empty() && text[0] == '[') {
    const size_t close = text.find(']');
    if (close == std::string::npos) return false;
    *host = text.substr(1, close - 1);
    const std::string rest = text.substr(close + 1);
    if (rest.empty()) *port = "";
    else if (rest[0] == ':') *port = rest.substr(1);
    else return false;
    return true;
  }
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos) {
    *host = text;
    *port = "";
  } else {
    *host = text.substr(0, colon);
    *port = text.substr(colon + 1);
  }
  return host->find(':') == std::string::npos;
}

}  // namespace

bool HostAllowed(const std::string& header, const std::string& bind, int port) {
  std::string host, port_text;
  if (header.size() > 255 || !SplitHostPort(Lower(header), &host, &port_text)) return false;
  const std::string expected_port = std::to_string(port);
  if (port_text != expected_port && !(port == 80 && port_text.empty())) return false;
  if (host == "localhost" || host == "127.0.0.1" || host == "::1") return true;
  if (IsLoopback(bind)) return false;
  // Bound to an address of the network: that address, or any address literal when bound to all
  // of them; never a name (a name can be rebound to another address by its DNS).
  if (bind == "0.0.0.0" || bind == "::") return IsIpLiteral(host);
  return host == Lower(bind);
}

bool OriginAllowed(const std::string& origin, const std::string& bind, int port) {
  const std::string prefix = "http://";
  const std::string o = Lower(origin);
  if (o.compare(0, prefix.size(), prefix) != 0) return false;
  return HostAllowed(o.substr(prefix.size()), bind, port);
}

namespace {

// ---------------------------------------------------------------------------------------------
// A page's state, shared by its WebSocket (I/O thread) and the render thread.
class WsSession;
struct Client {
  std::mutex mutex;
  std::optional<ViewState> wanted;     // the latest view the page sent
  uint64_t wanted_seq = 0;
  uint64_t wanted_generation = 0;      // bumped by every view message
  std::deque<ClientMessage> picks;     // picks and sections, answered in turn
  int frames_outstanding = 0;          // posted to the socket, not yet written or dropped
  bool closed = false;
  std::weak_ptr<WsSession> session;
  // Render thread only.
  std::unique_ptr<ProgressiveImage> image;
  uint64_t image_generation = 0, image_seq = 0;
  int steps = 0;                       // steps since the image started
  std::optional<ViewState> last_state;  // of the image drawn (picks, sections)
  std::atomic<uint64_t> generation{0};  // wanted_generation, for cancelling without the lock
  // Export thread: bumped by each section request the render thread hands over (a running export
  // of an older one is cancelled); `gone` when the page closed.
  std::atomic<uint64_t> export_generation{0};
  std::atomic<bool> gone{false};
};

// A section export waiting for the export thread.
struct ExportJob {
  std::shared_ptr<Client> client;
  ClientMessage message;
  ViewState state;
  uint64_t generation = 0;
};

}  // namespace

namespace {
// The message that gives a page the scene of an archive that replaced the one it loaded.
std::string SceneMessage(const std::string& scene_json) { return "{\"type\":\"scene\",\"scene\":" + scene_json + "}"; }

// What the pages are drawn from: an archive, its source and its renderer (Server::Replace).
struct Drawn {
  const ViewerSource* source = nullptr;
  const render::Archive* archive = nullptr;
  RangeRenderer renderer;
};
}  // namespace

struct Server::Impl {
  ServerOptions options;
  // Render thread only (it applies a Replace between steps).
  Drawn drawn;
  const render::Archive& archive() const { return *drawn.archive; }
  std::optional<Drawn> replacement;   // under `mutex`: to be applied by the render thread
  uint64_t replacements = 0;          // under `mutex`: replacements applied
  std::string token;
  std::string scene_json;             // under `mutex` once the server runs
  std::optional<FieldLegend> legend;  // points coloured by a field: picks read its value back
  // Caps: pages reserved from their accepted upgrade, accumulation pixels of the pages' last
  // views, sockets open. Raised on the I/O thread; lowered wherever a session ends (also when
  // `io` destroys the handlers still queued at the end: so declared before it).
  std::atomic<int> pages_reserved{0}, connections{0};
  std::atomic<uint64_t> pixels_reserved{0};
  net::io_context io{1};
  tcp::acceptor acceptor{io};
  int port = 0;

  std::mutex mutex;                    // clients, cv, exports, export_cv
  std::condition_variable cv;
  std::list<std::shared_ptr<Client>> clients;
  bool stopping = false;
  std::thread render_thread;
  std::deque<ExportJob> exports;
  std::condition_variable export_cv;
  std::thread export_thread;

  std::atomic<uint64_t> view_messages{0};  // every page's camera messages: a refinement gives way
  net::steady_timer accept_timer{io};
  uint64_t accept_streak = 0, refuse_streak = 0;  // I/O thread: failed accepts, refused connections in a row

  std::atomic<uint64_t> requests{0}, refused{0}, pages{0}, open_pages{0}, frames_sent{0}, frames_dropped{0},
      images_abandoned{0}, bad_messages{0}, accept_errors{0}, connections_refused{0}, views_refused{0},
      previews{0}, steps_preempted{0}, sections{0}, sections_cancelled{0}, pages_closed_unread{0};

  Impl(const ServerOptions& o, const ViewerSource& s, const render::Archive& a, RangeRenderer r)
      : options(o), drawn{&s, &a, std::move(r)} {}

  std::string SceneJson() {
    std::lock_guard<std::mutex> lock(mutex);
    return scene_json;
  }
  // Render thread: draws from the replacement from now on; every page's image starts again
  // with its latest view, and each open page gets the new scene.
  void ApplyReplacement(const std::vector<std::shared_ptr<Client>>& pages);

  void Log(const std::string& line) {
    if (options.log) options.log(line);
  }
  void Wake() { cv.notify_all(); }

  void Accept();
  void RenderLoop();
  void ExportLoop();
  bool StepClient(const std::shared_ptr<Client>& c);
  std::string Pick(const ClientMessage& pick, const ViewState& state);
  void QueueExport(const std::shared_ptr<Client>& c, const ClientMessage& m, const ViewState& state);
  // The log's form of a request target: its path (the query, which may hold the token, dropped).
  std::string LoggedPath(std::string_view target) const;
};

// A socket counted against max_connections while a session holds it.
struct ConnectionSlot {
  Server::Impl* server;
  explicit ConnectionSlot(Server::Impl* s) : server(s) { ++server->connections; }
  ~ConnectionSlot() { --server->connections; }
  ConnectionSlot(const ConnectionSlot&) = delete;
  ConnectionSlot& operator=(const ConnectionSlot&) = delete;
};

namespace {

// ---------------------------------------------------------------------------------------------
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  // Holds one of the server's page reservations (pages_reserved, taken by the HTTP session that
  // accepted the upgrade) until it ends, whether or not the handshake completes.
  WsSession(tcp::socket&& socket, Server::Impl* server, std::shared_ptr<ConnectionSlot> slot)
      : ws_(std::move(socket)), server_(server), slot_(std::move(slot)) {}
  ~WsSession() {
    --server_->pages_reserved;
    server_->pixels_reserved -= pixels_;
  }

  void Start(http::request<http::string_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxMessageBytes);
    ws_.async_accept(request, beast::bind_front_handler(&WsSession::OnAccept, shared_from_this()));
  }

  // Render thread -> I/O thread.
  void QueueFrame(std::shared_ptr<const std::string> frame) {
    if (frame_) {  // the page has not taken the last one: the newer replaces it
      ++server_->frames_dropped;
      Done(1);
    }
    frame_ = std::move(frame);
    Write();
  }
  void QueueText(std::string text) {
    if (closed_) return;
    if (texts_.size() >= kMaxQueuedTexts || queued_bytes_ + text.size() > kMaxQueuedTextBytes) {
      ++server_->pages_closed_unread;
      server_->Log("view: closed a page that does not read its replies (" + std::to_string(texts_.size()) +
                   " waiting, " + std::to_string(queued_bytes_ >> 20) + " MiB)");
      Close();
      return;
    }
    queued_bytes_ += text.size();
    texts_.push_back(std::move(text));
    Write();
  }

 private:
  void OnAccept(beast::error_code ec) {
    if (ec) return;  // the reservation ends with this session
    client_ = std::make_shared<Client>();
    client_->session = weak_from_this();
    std::string scene;  // a page that may have loaded the scene before a Replace: the current one
    {
      std::lock_guard<std::mutex> lock(server_->mutex);
      server_->clients.push_back(client_);
      if (server_->replacements > 0) scene = SceneMessage(server_->scene_json);
    }
    ++server_->pages;
    ++server_->open_pages;
    if (!scene.empty()) QueueText(std::move(scene));
    Read();
  }

  void Read() { ws_.async_read(buffer_, beast::bind_front_handler(&WsSession::OnRead, shared_from_this())); }

  void OnRead(beast::error_code ec, size_t) {
    if (ec) {
      Close();
      return;
    }
    if (!ws_.got_text()) {
      Refuse("binary messages are not part of the protocol");
      return;
    }
    const std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    ClientMessage message;
    try {
      message = ParseClientMessage(text);
    } catch (const std::invalid_argument& e) {
      Refuse(e.what());
      return;
    }
    if (message.type == MessageType::kView && !ReservePixels(message.view)) {
      Read();
      return;
    }
    {
      std::lock_guard<std::mutex> lock(client_->mutex);
      if (message.type == MessageType::kView) {
        client_->wanted = message.view;
        client_->wanted_seq = message.seq;
        client_->generation = ++client_->wanted_generation;
        ++server_->view_messages;
      } else if (client_->picks.size() < 4) {
        client_->picks.push_back(message);
      }
    }
    server_->Wake();
    Read();
  }

  // The pixels of a page's view count against max_pixels (its previous view's are given back);
  // over it, the view is refused with a message and the page keeps its last one.
  bool ReservePixels(const ViewState& view) {
    const uint64_t want = static_cast<uint64_t>(view.camera.width) * static_cast<uint64_t>(view.camera.height);
    const uint64_t cap = server_->options.max_pixels;
    uint64_t now = server_->pixels_reserved.load();
    for (;;) {
      const uint64_t others = now - pixels_;
      if (others + want > cap) {
        ++server_->views_refused;
        const std::string why = "view of " + std::to_string(view.camera.width) + "x" + std::to_string(view.camera.height) +
                                " pixels refused: the open pages hold " + std::to_string(others) + " of the " +
                                std::to_string(cap) + " pixels this server accumulates (candi view --max-pixels); " +
                                "use a smaller window or close another page";
        if (!refusal_logged_) server_->Log("view: " + why + " (logged once a page)");
        refusal_logged_ = true;
        QueueText(ErrorReply(why));
        return false;
      }
      if (server_->pixels_reserved.compare_exchange_weak(now, others + want)) break;
    }
    pixels_ = want;
    return true;
  }

  // A malformed message: say why, then close with a policy error.
  void Refuse(const std::string& why) {
    ++server_->bad_messages;
    server_->Log("view: closed a page's socket: " + why);
    closing_ = true;
    texts_.push_back(ErrorReply(why));
    Write();
  }

  void Write() {
    if (writing_ || !ws_.is_open()) return;
    if (!texts_.empty()) {
      writing_ = true;
      in_flight_text_ = std::move(texts_.front());
      texts_.pop_front();
      queued_bytes_ -= std::min(queued_bytes_, in_flight_text_.size());
      ws_.text(true);
      ws_.async_write(net::buffer(in_flight_text_),
                      beast::bind_front_handler(&WsSession::OnWrite, shared_from_this(), false));
    } else if (closing_) {
      writing_ = true;
      ws_.async_close(websocket::close_code::policy_error,
                      [self = shared_from_this()](beast::error_code) { self->Close(); });
    } else if (frame_) {
      writing_ = true;
      in_flight_frame_ = std::move(frame_);
      frame_.reset();
      ws_.binary(true);
      ws_.async_write(net::buffer(*in_flight_frame_),
                      beast::bind_front_handler(&WsSession::OnWrite, shared_from_this(), true));
    }
  }

  void OnWrite(bool frame, beast::error_code ec, size_t) {
    writing_ = false;
    if (frame) {
      in_flight_frame_.reset();
      if (!ec) ++server_->frames_sent;
      Done(1);
    }
    if (ec) {
      Close();
      return;
    }
    Write();
  }

  // Frames written or dropped: the render thread may draw more for this page.
  void Done(int n) {
    if (!client_) return;
    {
      std::lock_guard<std::mutex> lock(client_->mutex);
      client_->frames_outstanding -= n;
    }
    server_->Wake();
  }

  void Close() {
    if (closed_) return;
    closed_ = true;
    if (frame_) {
      frame_.reset();
      Done(1);
    }
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
    if (client_) {
      {
        std::lock_guard<std::mutex> lock(client_->mutex);
        client_->closed = true;
        client_->generation = ~uint64_t{0};  // abandons an image being drawn
      }
      client_->gone = true;                  // and an export running for it
      --server_->open_pages;
      server_->Wake();
    }
  }

  websocket::stream<beast::tcp_stream> ws_;
  Server::Impl* server_;
  std::shared_ptr<ConnectionSlot> slot_;
  beast::flat_buffer buffer_;
  std::shared_ptr<Client> client_;
  uint64_t pixels_ = 0;  // reserved for this page's last view
  bool refusal_logged_ = false;
  std::deque<std::string> texts_;
  size_t queued_bytes_ = 0;
  std::string in_flight_text_;
  std::shared_ptr<const std::string> frame_, in_flight_frame_;
  bool writing_ = false, closing_ = false, closed_ = false;
};

// ---------------------------------------------------------------------------------------------
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, Server::Impl* server)
      : stream_(std::move(socket)), server_(server), slot_(std::make_shared<ConnectionSlot>(server)) {}
  void Start() { Read(); }

 private:
  using Response = http::response<http::string_body>;

  void Read() {
    parser_.emplace();
    parser_->header_limit(kHeaderLimit);
    parser_->body_limit(kBodyLimit);
    stream_.expires_after(std::chrono::seconds(authorised_ ? kIdleSeconds : kUnauthorisedSeconds));
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&HttpSession::OnRead, shared_from_this()));
  }

  void OnRead(beast::error_code ec, size_t) {
    if (ec == http::error::end_of_stream || ec == net::error::operation_aborted || ec == beast::error::timeout ||
        ec == net::error::eof || ec == net::error::connection_reset) {
      Shutdown();
      return;
    }
    if (ec) {  // malformed: status by cause, then close
      http::status status = http::status::bad_request;
      if (ec == http::error::header_limit) status = http::status::request_header_fields_too_large;
      if (ec == http::error::body_limit) status = http::status::payload_too_large;
      Send(Plain(status, 11, false, std::string("bad request: ") + ec.message()));
      return;
    }
    http::request<http::string_body> request = parser_->release();
    ++server_->requests;
    Handle(std::move(request));
  }

  Response Plain(http::status status, unsigned version, bool keep_alive, const std::string& text) {
    Response r{status, version};
    r.set(http::field::content_type, "text/plain; charset=utf-8");
    r.keep_alive(keep_alive);
    r.body() = text + "\n";
    if (static_cast<int>(status) >= 400) ++server_->refused;
    return r;
  }

  void Handle(http::request<http::string_body>&& request) {
    const unsigned version = request.version();
    const bool keep_alive = request.keep_alive();
    auto refuse = [&](http::status status, const std::string& why) {
      server_->Log("view: refused " + std::string(request.method_string()).substr(0, 20) + " " +
                   server_->LoggedPath(request.target()) + ": " + why);
      Send(Plain(status, version, false, why));
    };
    const std::string host(request[http::field::host]);
    const int port = server_->port;
    const std::string& bind = server_->options.host;
    if (!HostAllowed(host, bind, port)) return refuse(http::status::forbidden, "Host '" + host.substr(0, 100) + "' is not this server");
    if (request.count(http::field::origin) &&
        !OriginAllowed(std::string(request[http::field::origin]), bind, port)) {
      return refuse(http::status::forbidden, "Origin not allowed");
    }
    if (request.target().size() > kTargetLimit) return refuse(http::status::uri_too_long, "target too long");
    const std::string target(request.target());
    const size_t q = target.find('?');
    const std::string path = target.substr(0, q);
    const std::string query = q == std::string::npos ? "" : target.substr(q + 1);
    // The token: from the query (?token=) or the cookie.
    std::string given, from_cookie;
    for (size_t start = 0; start <= query.size();) {
      size_t end = query.find('&', start);
      if (end == std::string::npos) end = query.size();
      const std::string pair = query.substr(start, end - start);
      if (pair.compare(0, 6, "token=") == 0) given = pair.substr(6);
      start = end + 1;
    }
    // Cookies are shared by every port of a host: one name per server's port.
    const std::string cookie_name = "candi_token_" + std::to_string(port) + "=";
    const std::string cookies(request[http::field::cookie]);
    for (size_t at = cookies.find(cookie_name); at != std::string::npos; at = cookies.find(cookie_name, at + 1)) {
      if (at == 0 || cookies[at - 1] == ' ' || cookies[at - 1] == ';') {
        const size_t begin = at + cookie_name.size(), end = cookies.find(';', at);
        from_cookie = cookies.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
      }
    }
    const bool authorised = ConstantTimeEqual(given, server_->token) || ConstantTimeEqual(from_cookie, server_->token);
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      return refuse(http::status::method_not_allowed, "only GET and HEAD");
    }
    if (!authorised) {
      return refuse(http::status::forbidden,
                    "missing or wrong access token: open the address `candi view` printed (with ?token=...)");
    }
    authorised_ = true;
    if (path == "/ws") {
      if (!websocket::is_upgrade(request)) return refuse(http::status::bad_request, "expected a WebSocket upgrade");
      // The page is counted from here (not from the finished handshake), so simultaneous upgrades
      // cannot pass the cap; the session gives its place back however it ends.
      const int max = server_->options.max_clients;
      if (++server_->pages_reserved > max) {
        --server_->pages_reserved;
        return refuse(http::status::service_unavailable,
                      "too many pages open (" + std::to_string(max) + ", the most this viewer serves at once)");
      }
      stream_.expires_never();
      std::make_shared<WsSession>(stream_.release_socket(), server_, slot_)->Start(std::move(request));
      return;
    }
    Response r{http::status::ok, version};
    if (path == "/api/scene") {
      r.set(http::field::content_type, "application/json");
      r.body() = server_->SceneJson();
    } else {
      const WebAsset* asset = FindWebAsset(path == "/" ? "/index.html" : path);
      if (asset == nullptr) return refuse(http::status::not_found, "not found");
      r.set(http::field::content_type, asset->content_type);
      r.body().assign(reinterpret_cast<const char*>(asset->data), asset->size);
    }
    if (ConstantTimeEqual(given, server_->token)) {
      r.set(http::field::set_cookie, cookie_name + server_->token + "; Path=/; HttpOnly; SameSite=Strict");
    }
    r.set(http::field::cache_control, "no-store");
    r.set("X-Content-Type-Options", "nosniff");
    r.set("Referrer-Policy", "no-referrer");
    r.set("Content-Security-Policy",
          "default-src 'self'; img-src 'self' blob: data:; connect-src 'self' ws://" + host +
              "; style-src 'self'; script-src 'self'; frame-ancestors 'none'");
    r.keep_alive(keep_alive);
    r.prepare_payload();
    if (request.method() == http::verb::head) r.body().clear();
    Send(std::move(r));
  }

  void Send(Response&& response) {
    auto shared = std::make_shared<Response>(std::move(response));
    shared->prepare_payload();
    http::async_write(stream_, *shared,
                      [self = shared_from_this(), shared](beast::error_code ec, size_t) {
                        if (ec || shared->need_eof()) return self->Shutdown();
                        self->Read();
                      });
  }

  void Shutdown() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    stream_.socket().close(ignored);
  }

  beast::tcp_stream stream_;
  Server::Impl* server_;
  std::shared_ptr<ConnectionSlot> slot_;  // passed on to the page when the connection upgrades
  bool authorised_ = false;               // a request showed the token
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

void Server::Impl::Accept() {
  acceptor.async_accept(net::make_strand(io), [this](beast::error_code ec, tcp::socket socket) {
    if (!acceptor.is_open()) return;
    if (ec) {
      // Out of descriptors (EMFILE), or the like: the connection stays in the backlog; pause
      // instead of retrying at once (which would spin the I/O thread).
      ++accept_errors;
      if (accept_streak++ == 0) {
        Log("view: cannot accept a connection (" + ec.message() + "); retrying every " +
            std::to_string(kAcceptPause.count()) + " ms");
      }
      accept_timer.expires_after(kAcceptPause);
      accept_timer.async_wait([this](beast::error_code wait) {
        if (!wait && acceptor.is_open()) Accept();
      });
      return;
    }
    if (accept_streak > 0) {
      Log("view: accepting connections again after " + std::to_string(accept_streak) + " failed accepts");
      accept_streak = 0;
    }
    boost::system::error_code ignored;
    if (connections.load() >= options.max_connections) {
      ++connections_refused;
      if (refuse_streak++ == 0) {
        Log("view: " + std::to_string(options.max_connections) + " connections open (the most); closing new ones");
      }
      socket.close(ignored);
    } else {
      refuse_streak = 0;
      // Frames are large writes whose last segment would otherwise wait for the page's delayed
      // ACK (Nagle): ~40 ms added to every frame.
      socket.set_option(tcp::no_delay(true), ignored);
      std::make_shared<HttpSession>(std::move(socket), this)->Start();
    }
    Accept();
  });
}

std::string Server::Impl::LoggedPath(std::string_view target) const {
  std::string path(target.substr(0, std::min(target.find('?'), size_t{200})));
  // A token pasted into the path stays out of the log too.
  for (size_t at = path.find(token); !token.empty() && at != std::string::npos; at = path.find(token)) {
    path.replace(at, token.size(), "...");
  }
  return path;
}

std::string Server::Impl::Pick(const ClientMessage& pick, const ViewState& state) {
  const Eigen::Vector3d& origin = archive().manifest().frame.origin;
  render::Camera local = state.camera;
  local.eye -= origin;
  local.target -= origin;
  PickOptions o;
  o.repeat_level = state.settings.EffectiveRepeatLevel();
  o.seed = state.settings.seed;
  o.layer_fraction = state.settings.layer_fraction;
  o.clip = state.settings.clip.ToLocal(origin);
  const PickResult r = PickPoint(archive(), local, pick.x, pick.y, o);
  std::vector<PickHitWorld> hits;
  for (const PickHit& h : r.hits) {
    PickHitWorld w;
    w.layer = h.layer;
    w.world = h.local + origin;
    w.depth = h.depth;
    if (legend) {
      w.field = true;
      w.value = legend->ValueOfColour(h.colour, &w.value_half_width);
    }
    hits.push_back(w);
  }
  return PickReply(pick.seq, hits);
}

// Hands a section request to the export thread: at most one per page (a newer request cancels
// the page's running export and replaces a waiting one).
void Server::Impl::QueueExport(const std::shared_ptr<Client>& c, const ClientMessage& m, const ViewState& state) {
  std::optional<uint64_t> replaced;
  {
    std::lock_guard<std::mutex> lock(mutex);
    const uint64_t generation = ++c->export_generation;
    for (auto it = exports.begin(); it != exports.end(); ++it) {
      if (it->client == c) {
        replaced = it->message.seq;
        exports.erase(it);
        break;
      }
    }
    exports.push_back({c, m, state, generation});
  }
  export_cv.notify_one();
  if (replaced) {
    ++sections_cancelled;
    if (std::shared_ptr<WsSession> session = c->session.lock()) {
      net::post(io, [session, seq = *replaced] {
        session->QueueText(ErrorReply("section " + std::to_string(seq) + " cancelled: a newer one replaced it"));
      });
    }
  }
}

void Server::Impl::ExportLoop() {
  for (;;) {
    ExportJob job;
    {
      std::unique_lock<std::mutex> lock(mutex);
      export_cv.wait(lock, [&] { return stopping || !exports.empty(); });
      if (stopping) return;
      job = std::move(exports.front());
      exports.pop_front();
    }
    const std::shared_ptr<Client>& c = job.client;
    const auto start = std::chrono::steady_clock::now();
    const double limit = options.section_seconds;
    SectionControl control;
    control.max_points = options.section_max_points;
    control.checkpoint = [&] {
      if (c->gone || c->export_generation.load() != job.generation) throw Cancelled{};
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (stopping) throw Cancelled{};
      }
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > limit) {
        throw std::runtime_error("stopped after " + FormatSignificant(limit, 6) + " s" +
                                 " (the viewer's limit): cut a thinner slab, clip it, or use candi section");
      }
    };
    std::string reply;
    try {
      if (!options.section) throw std::runtime_error("this viewer cannot export sections");
      control.checkpoint();
      reply = options.section(job.message.seq, job.message.section, job.state, control);
      ++sections;
    } catch (const Cancelled&) {
      ++sections_cancelled;
      if (c->gone) continue;
      reply = ErrorReply("section " + std::to_string(job.message.seq) + " cancelled: a newer one replaced it");
    } catch (const std::exception& e) {  // a corrupt chunk, too many points, the time limit
      reply = ErrorReply(std::string("section failed: ") + e.what());
    }
    if (std::shared_ptr<WsSession> session = c->session.lock()) {
      net::post(io, [session, reply = std::move(reply)]() mutable { session->QueueText(std::move(reply)); });
    }
  }
}

// One step of one page: its picks, then (if its image is not converged and the page has room
// for a frame) the next batch of ensembles. Returns false when the page had nothing to do.
bool Server::Impl::StepClient(const std::shared_ptr<Client>& c) {
  std::optional<ClientMessage> pick;
  std::optional<ViewState> restart;
  uint64_t generation = 0, seq = 0;
  {
    std::lock_guard<std::mutex> lock(c->mutex);
    if (c->closed) return false;
    const bool moved = c->wanted && c->wanted_generation != c->image_generation;
    if (!c->picks.empty() && c->last_state) {
      pick = c->picks.front();
      c->picks.pop_front();
    } else if (c->frames_outstanding >= 2 || (c->frames_outstanding == 1 && !moved)) {
      // The page has frames to take first. A new camera's frame may wait behind the one being
      // written (it replaces any other), but a converging image waits for the page.
      return false;
    } else if (moved) {
      restart = c->wanted;
      generation = c->wanted_generation;
      seq = c->wanted_seq;
    } else if (!c->image || c->image->converged()) {
      return false;
    }
  }
  std::shared_ptr<WsSession> session = c->session.lock();
  if (!session) return false;
  if (pick && pick->type == MessageType::kSection) {
    QueueExport(c, *pick, *c->last_state);
    return true;
  }
  if (pick) {
    std::string reply;
    try {
      reply = Pick(*pick, *c->last_state);
    } catch (const std::exception& e) {  // a corrupt chunk
      reply = ErrorReply(std::string("pick failed: ") + e.what());
    }
    net::post(io, [session, reply] { session->QueueText(reply); });
    return true;
  }
  if (restart) {
    if (!c->image) c->image = std::make_unique<ProgressiveImage>(archive(), drawn.renderer, options.threads);
    if (c->image->ensembles() > 0 && !c->image->converged()) ++images_abandoned;
    try {
      c->image->Start(*restart);
    } catch (const std::exception& e) {  // Camera::Check: the parser has checked it already
      net::post(io, [session, m = ErrorReply(e.what())] { session->QueueText(m); });
      c->image_generation = generation;
      c->image.reset();
      return true;
    }
    c->image_generation = generation;
    c->image_seq = seq;
    c->steps = 0;
    c->last_state = *restart;
  }
  ProgressiveImage& image = *c->image;
  int count = StepPolicy{options.first_frame_ms, options.step_ms}.Ensembles(image.ms_per_ensemble(), c->steps);
  const uint64_t mine = c->image_generation;
  double ms = 0;
  // The first step of an image (its preview) is abandoned only when its page closes: a page that
  // sends cameras faster than they can be drawn still gets a frame of a recent one each turn. Its
  // cost is bounded instead: at most preview_pixels written, else a sampled preview.
  // Refinement steps are abandoned as soon as the camera moves, and give way to another page's
  // new camera once they have run step_ms (they are drawn again on this page's next turn).
  const bool first = c->steps == 0;
  double sample = 1;
  if (first) {
    const double per = image.EnsembleFootprint(), budget = options.preview_pixels;
    if (per * count > budget) count = std::max(1, static_cast<int>(budget / per));
    if (per > budget) sample = std::max(budget / per, 1e-9);
  }
  const uint64_t views_before = view_messages.load();
  const auto start = std::chrono::steady_clock::now();
  // Polled by the drawing threads (every few thousand points): reads atomics and the clock only.
  auto cancel = [&] {
    const uint64_t now = c->generation.load();
    if (first) return now == ~uint64_t{0};
    if (now != mine) return true;
    return view_messages.load() != views_before &&
           std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() > options.step_ms;
  };
  try {
    ms = image.Step(count, cancel, sample);
  } catch (const Cancelled&) {
    ++(!first && c->generation.load() == mine ? steps_preempted : images_abandoned);
    return true;
  } catch (const std::exception& e) {  // a corrupt chunk, out of memory
    Log(std::string("view: render failed: ") + e.what());
    net::post(io, [session, m = ErrorReply(std::string("render failed: ") + e.what())] { session->QueueText(m); });
    c->image.reset();
    return true;
  }
  ++c->steps;
  if (image.sampled()) ++previews;
  double gain = 1;
  const Image8 pixels = image.Image(&gain);
  FrameHeader h;
  h.seq = c->image_seq;
  h.ensembles = image.ensembles();
  h.repeat_level = image.repeat_level();
  h.png = image.converged();
  h.width = pixels.width();
  h.height = pixels.height();
  h.gain = gain;
  h.render_ms = ms;
  h.sample = image.sample();
  auto frame = std::make_shared<const std::string>(
      FrameMessage(h, h.png ? io::EncodePng(pixels, {}, io::PngCompression::kFast)
                            : io::EncodeJpeg(pixels, options.jpeg_quality)));
  {
    std::lock_guard<std::mutex> lock(c->mutex);
    ++c->frames_outstanding;
  }
  net::post(io, [session, frame] { session->QueueFrame(frame); });
  return true;
}

void Server::Impl::ApplyReplacement(const std::vector<std::shared_ptr<Client>>& pages) {
  const std::string message = SceneMessage(SceneJson());
  for (const std::shared_ptr<Client>& c : pages) {
    c->image.reset();  // drawn from the archive replaced
    std::lock_guard<std::mutex> lock(c->mutex);
    c->image_generation = ~uint64_t{0};  // != wanted_generation: the latest view is drawn again
    c->last_state.reset();               // picks wait for it
    if (std::shared_ptr<WsSession> session = c->session.lock()) {
      net::post(io, [session, message] { session->QueueText(message); });
    }
  }
}

void Server::Impl::RenderLoop() {
  size_t turn = 0;
  for (;;) {
    std::vector<std::shared_ptr<Client>> snapshot;
    bool replaced = false;
    {
      std::unique_lock<std::mutex> lock(mutex);
      if (stopping) return;
      clients.remove_if([](const std::shared_ptr<Client>& c) {
        std::lock_guard<std::mutex> l(c->mutex);
        return c->closed;
      });
      snapshot.assign(clients.begin(), clients.end());
      if (replacement) {
        drawn = std::move(*replacement);
        replacement.reset();
        scene_json = drawn.source->ToJson(drawn.archive->manifest());
        legend = drawn.source->legend;
        ++replacements;
        replaced = true;
      }
    }
    if (replaced) ApplyReplacement(snapshot);
    // Round robin: every page in turn, starting after the one served last.
    bool worked = false;
    for (size_t i = 0; i < snapshot.size() && !worked; ++i) {
      const size_t k = (turn + i) % snapshot.size();
      if (StepClient(snapshot[k])) {
        worked = true;
        turn = k + 1;
      }
    }
    if (!worked) {
      std::unique_lock<std::mutex> lock(mutex);
      if (stopping) return;
      cv.wait_for(lock, std::chrono::milliseconds(200));
    }
  }
}

void ServerOptions::Check() const {
  CANDI_CHECK_OPTION_IN(port, 0, 65535);
  const bool url_safe = std::all_of(token.begin(), token.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~';
  });
  CANDI_CHECK_OPTION(url_safe, token, "letters, digits, - . _ ~ (or empty: random)");
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
  CANDI_CHECK_OPTION_GE(max_clients, 1);
  CANDI_CHECK_OPTION_GE(max_connections, max_clients);
  CANDI_CHECK_OPTION(max_pixels >= 1, max_pixels, ">= 1");
  CANDI_CHECK_OPTION(preview_pixels > 0 && std::isfinite(preview_pixels), preview_pixels, "finite and > 0");
  CANDI_CHECK_OPTION(section_seconds > 0 && std::isfinite(section_seconds), section_seconds, "finite and > 0 s");
  CANDI_CHECK_OPTION(section_max_points >= 1, section_max_points, ">= 1");
  CANDI_CHECK_OPTION(first_frame_ms > 0 && std::isfinite(first_frame_ms), first_frame_ms,
                     "finite and > 0");
  CANDI_CHECK_OPTION(step_ms >= first_frame_ms && std::isfinite(step_ms), step_ms,
                     "finite and >= first_frame_ms");
  CANDI_CHECK_OPTION_IN(jpeg_quality, 1, 100);
}

Server::Server(const ServerOptions& options, const ViewerSource& source, const render::Archive& archive,
               RangeRenderer renderer)
    : impl_(std::make_unique<Impl>(options, source, archive, std::move(renderer))) {
  options.Check();
  Impl& s = *impl_;
  s.token = options.token.empty() ? RandomToken() : options.token;
  s.scene_json = source.ToJson(archive.manifest());  // before any thread reads it
  s.legend = source.legend;
  boost::system::error_code ec;
  const net::ip::address address = net::ip::make_address(options.host == "localhost" ? "127.0.0.1" : options.host, ec);
  if (ec) throw std::runtime_error("--host '" + options.host + "': not an IP address");
  const tcp::endpoint endpoint(address, static_cast<unsigned short>(options.port));
  s.acceptor.open(endpoint.protocol(), ec);
  if (!ec) s.acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) s.acceptor.bind(endpoint, ec);
  if (!ec) s.acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) {
    throw std::runtime_error("cannot listen on " + options.host + ":" + std::to_string(options.port) + ": " + ec.message());
  }
  s.port = s.acceptor.local_endpoint().port();
  s.Accept();
  s.render_thread = std::thread([this] { impl_->RenderLoop(); });
  s.export_thread = std::thread([this] { impl_->ExportLoop(); });
}

Server::~Server() {
  Stop();
  if (impl_->render_thread.joinable()) impl_->render_thread.join();
  if (impl_->export_thread.joinable()) impl_->export_thread.join();
}

int Server::port() const { return impl_->port; }
const std::string& Server::token() const { return impl_->token; }

std::string Server::Url() const {
  std::string host = impl_->options.host;
  if (host == "0.0.0.0") host = "127.0.0.1";
  if (host.find(':') != std::string::npos) host = "[" + host + "]";
  return "http://" + host + ":" + std::to_string(impl_->port) + "/?token=" + impl_->token;
}

void Server::Run() { impl_->io.run(); }

void Server::Replace(const ViewerSource& source, const render::Archive& archive, RangeRenderer renderer) {
  Impl& s = *impl_;
  {
    std::lock_guard<std::mutex> lock(s.mutex);
    s.replacement = Drawn{&source, &archive, std::move(renderer)};
  }
  s.Wake();
}

void Server::Stop() {
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
    for (auto& c : impl_->clients) c->generation = ~uint64_t{0};
  }
  impl_->cv.notify_all();
  impl_->export_cv.notify_all();
  net::post(impl_->io, [this] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->accept_timer.cancel();
    impl_->io.stop();
  });
}

ServerStats Server::stats() const {
  const Impl& s = *impl_;
  ServerStats out;
  out.requests = s.requests;
  out.refused = s.refused;
  out.pages = s.pages;
  out.open_pages = s.open_pages;
  out.frames_sent = s.frames_sent;
  out.frames_dropped = s.frames_dropped;
  out.images_abandoned = s.images_abandoned;
  out.bad_messages = s.bad_messages;
  out.accept_errors = s.accept_errors;
  out.connections_refused = s.connections_refused;
  out.views_refused = s.views_refused;
  out.previews = s.previews;
  out.steps_preempted = s.steps_preempted;
  out.sections = s.sections;
  out.sections_cancelled = s.sections_cancelled;
  out.pages_closed_unread = s.pages_closed_unread;
  return out;
}

}  // namespace candi::view
