// Internal to the viewer's server: the state shared by view/server.cc (the HTTP and WebSocket
// sessions on the I/O thread, and the server's life) and view/server_loops.cc (the render and
// export threads). Included by those files only: it brings in Boost.Asio.
#pragma once

#include <boost/asio.hpp>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "view/server.h"

namespace candi::view {

namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace server_internal {

// What the render and export threads send a page: called on the I/O thread (net::post). The
// page's WebSocket session (view/server.cc) implements it.
class PageSink {
 public:
  virtual ~PageSink() = default;
  // A frame: it replaces one the page has not taken yet.
  virtual void QueueFrame(std::shared_ptr<const std::string> frame) = 0;
  // A text reply, in turn (a page that leaves too many unread is closed).
  virtual void QueueText(std::string text) = 0;
};

// A page's state, shared by its WebSocket (I/O thread) and the render thread.
struct Client {
  std::mutex mutex;
  std::optional<ViewState> wanted;     // the latest view the page sent
  uint64_t wanted_seq = 0;
  uint64_t wanted_generation = 0;      // bumped by every view message
  std::deque<ClientMessage> picks;     // picks and sections, answered in turn
  int frames_outstanding = 0;          // posted to the socket, not yet written or dropped
  bool closed = false;
  std::weak_ptr<PageSink> session;
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

// The message that gives a page the scene of an archive that replaced the one it loaded.
inline std::string SceneMessage(const std::string& scene_json) {
  return "{\"type\":\"scene\",\"scene\":" + scene_json + "}";
}

// What the pages are drawn from: an archive, its source and its renderer (Server::Replace).
struct Drawn {
  const ViewerSource* source = nullptr;
  const render::Archive* archive = nullptr;
  RangeRenderer renderer;
};

// A token of 32 hex digits from /dev/urandom.
std::string RandomToken();
// Equal strings, in a time that does not depend on where they differ.
bool ConstantTimeEqual(const std::string& a, const std::string& b);

}  // namespace server_internal

struct Server::Impl {
  ServerOptions options;
  // Render thread only (it applies a Replace between steps).
  server_internal::Drawn drawn;
  const render::Archive& archive() const { return *drawn.archive; }
  std::optional<server_internal::Drawn> replacement;   // under `mutex`: to be applied by the render thread
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
  std::list<std::shared_ptr<server_internal::Client>> clients;
  bool stopping = false;
  std::thread render_thread;
  std::deque<server_internal::ExportJob> exports;
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
  void ApplyReplacement(const std::vector<std::shared_ptr<server_internal::Client>>& pages);

  void Log(const std::string& line) {
    if (options.log) options.log(line);
  }
  void Wake() { cv.notify_all(); }

  void Accept();
  void RenderLoop();
  void ExportLoop();
  bool StepClient(const std::shared_ptr<server_internal::Client>& c);
  std::string Pick(const ClientMessage& pick, const ViewState& state);
  void QueueExport(const std::shared_ptr<server_internal::Client>& c, const ClientMessage& m,
                   const ViewState& state);
  // The log's form of a request target: its path (the query, which may hold the token, dropped).
  std::string LoggedPath(std::string_view target) const;
};

}  // namespace candi::view
