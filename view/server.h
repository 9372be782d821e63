// The viewer's web server: the page (view/web/, compiled in), the scene description, and one
// WebSocket per open page that carries cameras in and progressive frames out.
//
// Boost.Beast (HTTP/1.1 and WebSocket over Boost.Asio) does the parsing and framing; one I/O
// thread runs every socket, one render thread serves the pages in turn. A page's latest camera
// wins: an image whose camera moved is abandoned mid-draw (after its first frame, so a page
// moving faster than frames can be drawn still gets frames), and a frame the page has not yet
// taken is replaced by the next one (dropped, never queued), so a slow page never holds up the
// others.
//
// Safe by default: binds 127.0.0.1; every request needs the access token (in the URL's query,
// or the HttpOnly, SameSite=Strict cookie the page gets with it); the Host header must name the
// server (no DNS rebinding) and an Origin header, when present, the page's own origin; only the
// compiled-in assets and the API are served (no file system paths); GET and HEAD only; headers
// at most 8 KB, targets 2 KB, bodies 1 KB, messages kMaxMessageBytes. A malformed request gets a
// 4xx status and a malformed message a closed WebSocket; the server keeps serving.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "render/archive.h"
#include "view/progressive.h"
#include "view/source.h"

namespace candi::view {

struct ServerOptions {
  // Address to bind (an IP address or "localhost"); "0.0.0.0" serves the network. One that is not
  // an address, or cannot be bound, is std::runtime_error from the constructor, as a taken port is.
  std::string host = "127.0.0.1";
  int port = 0;  // [0, 65535]; 0: a free port
  // The access token: letters, digits and - . _ ~ (safe in a URL and a cookie); empty: 128
  // random bits, hex.
  std::string token;
  int threads = 0;       // render threads, [0, 256] (0: as TBB allows)
  int max_clients = 16;  // open pages at once, >= 1
  // The first frame after a camera change draws as many ensembles as fit this budget (ms, finite
  // and > 0); then each further step doubles it up to step_ms (ms, finite and >= first_frame_ms).
  double first_frame_ms = 40, step_ms = 400;
  int jpeg_quality = 85;                        // JPEG frames' quality, [1, 100]
  std::function<void(const std::string&)> log;  // one line per event worth knowing (may be null)
  // Answers a section message (its seq, the slab, the page's last view: layers and clipping)
  // with the reply's JSON text; null: sections are refused. Runs on the render thread.
  std::function<std::string(uint64_t seq, const SectionRequest&, const ViewState&)> section;
  void Check() const;  // throws std::invalid_argument naming the field
};

struct ServerStats {
  uint64_t requests = 0, refused = 0;         // HTTP requests answered, of them refused (4xx)
  uint64_t pages = 0, open_pages = 0;          // WebSockets opened, open now
  uint64_t frames_sent = 0, frames_dropped = 0, images_abandoned = 0, bad_messages = 0;
};

class Server {
 public:
  // `archive` and `source` must outlive the server. Binds at once (throws std::runtime_error
  // naming the address when it cannot).
  Server(const ServerOptions& options, const ViewerSource& source, const render::Archive& archive,
         RangeRenderer renderer);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  int port() const;
  const std::string& token() const;
  // The page's address, token included: http://127.0.0.1:PORT/?token=...
  std::string Url() const;
  // Serves until Stop() (from any thread).
  void Run();
  void Stop();
  ServerStats stats() const;

  struct Impl;  // server.cc (public for its sessions)

 private:
  std::unique_ptr<Impl> impl_;
};

// Parts of the checks, for tests and the fuzz target: true when `host` (a Host header) names a
// server bound to `bind` on `port`; true when `origin` (an Origin header) is that server's.
bool HostAllowed(const std::string& host, const std::string& bind, int port);
bool OriginAllowed(const std::string& origin, const std::string& bind, int port);

}  // namespace candi::view
