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
#include <deque>
#include <mutex>
#include <optional>
#include <string_view>
#include <thread>

#include "core/check.h"
#include "view/server_internal.h"
#include "view/web_assets.h"

namespace candi::view {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using server_internal::Client;
using server_internal::ConstantTimeEqual;
using server_internal::Drawn;
using server_internal::PageSink;
using server_internal::RandomToken;
using server_internal::SceneMessage;

namespace {

constexpr size_t kHeaderLimit = 8192, kTargetLimit = 2048, kBodyLimit = 1024;
// A connection has kUnauthorisedSeconds to send a request with the token, then kIdleSeconds
// between requests.
constexpr int kUnauthorisedSeconds = 5, kIdleSeconds = 30;
// Replies a page has not read: at most this many (or bytes), else the page is closed.
constexpr size_t kMaxQueuedTexts = 16, kMaxQueuedTextBytes = size_t{64} << 20;
constexpr std::chrono::milliseconds kAcceptPause(100);

}  // namespace

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
class WsSession : public PageSink, public std::enable_shared_from_this<WsSession> {
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
  void QueueFrame(std::shared_ptr<const std::string> frame) override {
    if (frame_) {  // the page has not taken the last one: the newer replaces it
      ++server_->frames_dropped;
      Done(1);
    }
    frame_ = std::move(frame);
    Write();
  }
  void QueueText(std::string text) override {
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
