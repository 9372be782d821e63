// The viewer's render thread (each page's image a step at a time, round robin, a Replace
// applied between steps) and its export thread (sections), behind view/server.h.
#include <algorithm>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/text_format.h"
#include "io/image/jpeg_io.h"
#include "io/image/png_io.h"
#include "view/server_internal.h"

namespace candi::view {

using server_internal::Client;
using server_internal::ExportJob;
using server_internal::PageSink;
using server_internal::SceneMessage;

std::string Server::Impl::Pick(const ClientMessage& pick, const ViewState& state) {
  const Eigen::Vector3d& origin = archive().manifest().frame.origin;
  render::Camera local = state.camera;
  local.eye -= origin;
  local.target -= origin;
  PickOptions o;
  o.spbr = state.settings.spbr;
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
    if (std::shared_ptr<PageSink> session = c->session.lock()) {
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
    if (std::shared_ptr<PageSink> session = c->session.lock()) {
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
  std::shared_ptr<PageSink> session = c->session.lock();
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
    if (std::shared_ptr<PageSink> session = c->session.lock()) {
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

}  // namespace candi::view
