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
//
// Bounded under hostile load: pages are counted when their upgrade is accepted (max_clients),
// sockets (max_connections) and accumulation pixels (max_pixels) are capped; a connection has 5 s
// to show the token (30 s idle once it has); a failed accept (no descriptors left) pauses 100 ms;
// a page that does not read its replies is closed; a first frame writes at most preview_pixels;
// a refinement step gives way to another page's new camera after step_ms; section exports run on
// a thread of their own, with a time and a size limit. Logs carry paths, never the token.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "render/archive.h"
#include "view/progressive.h"
#include "view/source.h"

namespace candi::view {

// What the section exporter gets besides the request: `checkpoint`, to call between steps of the
// work (it throws to abort it: the page closed, a newer request replaced this one, or the time
// limit passed), and the most points the slab may hold.
struct SectionControl {
  std::function<void()> checkpoint;
  uint64_t max_points = 0;
};

struct ServerOptions {
  // Address to bind (an IP address or "localhost"); "0.0.0.0" serves the network. One that is not
  // an address, or cannot be bound, is std::runtime_error from the constructor, as a taken port is.
  std::string host = "127.0.0.1";
  int port = 0;  // [0, 65535]; 0: a free port
  // The access token: letters, digits and - . _ ~ (safe in a URL and a cookie); empty: 128
  // random bits, hex.
  std::string token;
  int threads = 0;       // render threads, [0, 256] (0: as TBB allows)
  int max_clients = 16;  // open pages at once, >= 1 (counted from the accepted upgrade)
  // Sockets open at once (HTTP connections and pages), >= max_clients; more are closed at once.
  int max_connections = 256;
  // Accumulation pixels (16 bytes each) of all open pages together, >= 1: a view that would pass
  // it is refused with a message. The default holds 16 full-HD pages or two of 4096².
  uint64_t max_pixels = uint64_t{1} << 25;
  // The first frame after a camera change draws as many ensembles as fit this budget (ms, finite
  // and > 0); then each further step doubles it up to step_ms (ms, finite and >= first_frame_ms).
  double first_frame_ms = 40, step_ms = 400;
  // The most pixels a first frame may write (EnsembleFootprint: points times their area), > 0:
  // beyond it the first frame is a preview of a random share of one ensemble's points, so that
  // no view (huge points, one opaque ensemble) holds the render thread for long before a frame.
  double preview_pixels = 5e7;  // ~0.3 s of 64-pixel splats on the 2-core VM
  int jpeg_quality = 85;                        // JPEG frames' quality, [1, 100]
  std::function<void(const std::string&)> log;  // one line per event worth knowing (may be null)
  // Answers a section message (its seq, the slab, the page's last view: layers and clipping)
  // with the reply's JSON text; null: sections are refused. Runs on the export thread, one
  // export at a time, at most one per page (a newer request cancels the page's running one).
  std::function<std::string(uint64_t seq, const SectionRequest&, const ViewState&, const SectionControl&)> section;
  double section_seconds = 120;              // an export's time limit, s (finite, > 0)
  uint64_t section_max_points = 20'000'000;  // the most points an exported slab may hold, >= 1
  void Check() const;  // throws std::invalid_argument naming the field
};

struct ServerStats {
  uint64_t requests = 0, refused = 0;         // HTTP requests answered, of them refused (4xx)
  uint64_t pages = 0, open_pages = 0;          // WebSockets opened, open now
  uint64_t frames_sent = 0, frames_dropped = 0, images_abandoned = 0, bad_messages = 0;
  uint64_t accept_errors = 0;        // failed accepts (each followed by a 100 ms pause)
  uint64_t connections_refused = 0;  // closed at once: max_connections open
  uint64_t views_refused = 0;        // over max_pixels
  uint64_t previews = 0;             // first frames drawn as a sampled preview
  uint64_t steps_preempted = 0;      // refinement steps given up for another page's new camera
  uint64_t sections = 0, sections_cancelled = 0;  // exports answered; cancelled (page gone, replaced)
  uint64_t pages_closed_unread = 0;  // pages closed for not reading their replies
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
  // Draws from `archive` (described by `source`) instead, from the render thread's next turn
  // (any thread may call it): every open page's image starts again with its latest view, picks
  // wait for it, /api/scene answers the new scene and each open page gets it as
  // {"type": "scene", "scene": {...}}. candi view FILE shows a preview's archive first, then
  // the whole one. Both archives and sources must outlive the server (a section exporter may
  // still read the first).
  void Replace(const ViewerSource& source, const render::Archive& archive, RangeRenderer renderer);
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
