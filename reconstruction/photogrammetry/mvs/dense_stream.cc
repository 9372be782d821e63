#include "reconstruction/photogrammetry/mvs/dense_stream.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <list>
#include <map>
#include <memory>
#include <mutex>

#include <tbb/task_arena.h>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "core/timer.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::photogrammetry {

namespace {

namespace fs = std::filesystem;

struct Layout {
  explicit Layout(const std::string& workspace)
      : workspace(workspace), stereo(fs::path(workspace) / "stereo"), candi(stereo / "candi") {}
  std::string Raw(const std::string& name) const { return (candi / "raw" / (name + ".bin")).string(); }
  std::string Filtered(const std::string& name) const { return (candi / "filtered" / (name + ".bin")).string(); }
  std::string Tile(int k) const {
    char file[32];
    std::snprintf(file, sizeof(file), "tile_%06d.bin", k);
    return (candi / "fused" / file).string();
  }
  std::string Colmap(const char* kind, const std::string& name) const {
    return (stereo / kind / (name + ".geometric.bin")).string();
  }
  std::string workspace;
  fs::path stereo, candi;
};

// Least recently used images at the working resolution, at most `budget` bytes held by the cache
// (the ones a caller still holds stay alive beside it).
class ViewCache {
 public:
  ViewCache(const std::string& workspace, const StereoInput& model, double scale, uint64_t budget)
      : workspace_(workspace), model_(model), scale_(scale), budget_(budget) {}

  std::shared_ptr<const StereoView> Get(int v) {
    const auto it = entries_.find(v);
    if (it != entries_.end()) {
      order_.splice(order_.begin(), order_, it->second.second);
      return it->second.first;
    }
    StereoImage image = model_.images[v];
    image.image = ReadStereoImage(workspace_, image);
    auto view = std::make_shared<const StereoView>(PrepareStereoView(image, scale_));
    order_.push_front(v);
    entries_[v] = {view, order_.begin()};
    bytes_ += view->Bytes();
    peak_ = std::max(peak_, bytes_);
    while (bytes_ > budget_ && order_.size() > 1) {
      const int old = order_.back();
      order_.pop_back();
      bytes_ -= entries_[old].first->Bytes();
      entries_.erase(old);
    }
    return view;
  }
  uint64_t peak() const { return peak_; }

 private:
  const std::string& workspace_;
  const StereoInput& model_;
  double scale_;
  uint64_t budget_, bytes_ = 0, peak_ = 0;
  std::list<int> order_;
  std::map<int, std::pair<std::shared_ptr<const StereoView>, std::list<int>::iterator>> entries_;
};

// Filtered maps read from disk as fusion needs them.
class DiskMaps : public FusionMaps {
 public:
  DiskMaps(const Layout& layout, const StereoInput& model, const std::vector<PinholeCamera>& cameras)
      : layout_(layout), model_(model), cameras_(cameras) {}
  size_t size() const override { return cameras_.size(); }
  std::shared_ptr<const DepthNormalMap> Load(int v) const override {
    return std::make_shared<const DepthNormalMap>(ReadDepthMapFile(layout_.Filtered(model_.images[v].name), cameras_[v]));
  }

 private:
  const Layout& layout_;
  const StereoInput& model_;
  const std::vector<PinholeCamera>& cameras_;
};

std::string G(double v) {
  char s[32];
  std::snprintf(s, sizeof(s), "%.17g", v);
  return s;
}

// What each stage's files depend on, one line a stage (each line includes the one before).
std::vector<std::string> StageKeys(const DenseStreamOptions& o, const std::string& workspace, const StereoInput& model) {
  const PatchMatchOptions& s = o.stereo;
  std::string model_bytes;
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin", "cameras.txt", "images.txt", "points3D.txt"}) {
    const fs::path p = fs::path(workspace) / "sparse" / file;
    if (fs::exists(p)) model_bytes += std::string(file) + " " + Sha256OfFile(p.string()) + "\n";
  }
  std::string images;
  for (const StereoImage& image : model.images) {
    const fs::path p = fs::path(workspace) / "images" / image.name;
    std::error_code ec;
    const auto size = fs::file_size(p, ec);
    const auto time = fs::last_write_time(p, ec).time_since_epoch().count();
    images += image.name + " " + std::to_string(ec ? 0 : size) + " " + std::to_string(ec ? 0 : time) + "\n";
  }
  const std::string stereo = "maps 1 window " + std::to_string(s.window_radius) + " " + std::to_string(s.window_step) +
                             " iterations " + std::to_string(s.iterations) + " sources " +
                             std::to_string(s.num_source_views) + " " + G(s.min_triangulation_angle_deg) + " " +
                             G(s.max_distance_ratio) + " scale " + G(s.resolution_scale) + " depth " + G(s.depth_min) +
                             " " + G(s.depth_max) + " bilateral " + G(s.bilateral_sigma_color) + " " +
                             G(s.bilateral_sigma_spatial) + " texture " + G(s.min_texture) + " seed " +
                             std::to_string(s.seed) + "\n" + model_bytes + images;
  const std::string filter = "filter colmap " + std::to_string(o.keep_maps) + " checks " +
                             std::to_string(s.num_check_views) + " " + G(s.max_cost) + " " + G(s.max_reprojection_error_px) + " " +
                             G(s.max_depth_error) + " " + std::to_string(s.min_consistent_views);
  const FusionOptions& f = o.fusion;
  const std::string fusion = "fusion " + std::to_string(f.min_views) + " " + G(f.max_depth_error) + " " +
                             G(f.max_normal_error_deg) + " " + G(f.max_reprojection_error_px) + " " +
                             std::to_string(f.max_tile_views);
  const std::string a = Sha256Hex(stereo), b = Sha256Hex(a + filter), c = Sha256Hex(b + fusion);
  return {"stereo " + a, "filter " + b, "fusion " + c};
}

// Keeps the stages whose key is unchanged; removes the files of the first stage that changed and
// of every stage after it. True when anything was removed.
bool ReconcileSettings(const Layout& layout, const StereoInput& model, const std::vector<std::string>& keys) {
  const std::string path = (layout.candi / "settings.txt").string();
  std::vector<std::string> old;
  if (fs::exists(path)) {
    const std::string text = ReadFileToString(path);
    size_t start = 0;
    for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1)
      old.push_back(text.substr(start, end - start));
  }
  size_t same = 0;
  while (same < keys.size() && same < old.size() && old[same] == keys[same]) ++same;
  bool removed = false;
  auto remove = [&](const fs::path& p) { removed = fs::remove_all(p) > 0 || removed; };
  if (same < 3) remove(layout.candi / "fused");
  if (same < 2) {
    remove(layout.candi / "filtered");
    for (const StereoImage& image : model.images)
      for (const char* kind : {"depth_maps", "normal_maps"}) remove(layout.Colmap(kind, image.name));
  }
  if (same < 1) remove(layout.candi / "raw");
  std::string text;
  for (const std::string& k : keys) text += k + "\n";
  CreateParentFolder(path);
  WriteFileAtomic(path, text);
  return removed;
}

// The views that see each sparse point: the tracks, or (no tracks) the cameras it projects into.
std::vector<std::vector<int>> PointViews(const StereoInput& model) {
  if (!model.point_views.empty()) return model.point_views;
  std::vector<std::vector<int>> out(model.sparse_points.size());
  for (size_t k = 0; k < model.sparse_points.size(); ++k) {
    for (size_t v = 0; v < model.images.size(); ++v) {
      const PinholeCamera& cam = model.images[v].camera;
      const Eigen::Vector3d c = cam.ToCamera(model.sparse_points[k]);
      if (!(c.z() > 0)) continue;
      const Eigen::Vector2d uv = cam.Project(c);
      if (uv.x() >= 0 && uv.y() >= 0 && uv.x() < cam.width && uv.y() < cam.height) out[k].push_back(static_cast<int>(v));
    }
  }
  return out;
}

constexpr char kTileMagic[8] = {'C', 'A', 'N', 'D', 'I', 'F', 'T', '1'};

void WriteTileFile(const PointCloud& cloud, const std::string& path) {
  std::string out(kTileMagic, 8);
  const uint64_t n = cloud.size();
  out.append(reinterpret_cast<const char*>(&n), 8);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = cloud.WorldPosition(i);
    out.append(reinterpret_cast<const char*>(p.data()), 24);
    out.append(reinterpret_cast<const char*>(&cloud.colors[i]), 3);
    out.append(reinterpret_cast<const char*>(cloud.normals[i].data()), 12);
  }
  CreateParentFolder(path);
  WriteFileAtomic(path, out);
}

// The points of a complete tile file, from its header and size (InputError otherwise).
uint64_t TileFilePoints(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[16] = {};
  in.read(head, 16);
  uint64_t n = 0;
  std::memcpy(&n, head + 8, 8);
  std::error_code ec;
  const uint64_t bytes = fs::file_size(path, ec);
  if (!in || ec || std::memcmp(head, kTileMagic, 8) != 0 || n > bytes || bytes != 16 + n * 39)
    throw InputError(path, "", "not a complete candi fusion tile");
  return n;
}

void AppendTileFile(const std::string& path, PointCloud* cloud) {
  const std::string bytes = ReadFileToString(path);
  uint64_t n = 0;
  if (bytes.size() >= 16) std::memcpy(&n, bytes.data() + 8, 8);
  if (bytes.size() < 16 || bytes.compare(0, 8, kTileMagic, 8) != 0 || bytes.size() != 16 + n * 39)
    throw InputError(path, "", "not a complete candi fusion tile (" + std::to_string(bytes.size()) + " bytes)");
  const char* p = bytes.data() + 16;
  for (uint64_t i = 0; i < n; ++i, p += 39) {
    Eigen::Vector3d x;
    Rgb8 rgb;
    Eigen::Vector3f normal;
    std::memcpy(x.data(), p, 24);
    std::memcpy(&rgb, p + 24, 3);
    std::memcpy(normal.data(), p + 27, 12);
    cloud->positions.push_back(x);
    cloud->colors.push_back(rgb);
    cloud->normals.push_back(normal);
  }
}

bool Readable(const std::string& path, const std::function<void()>& read) {
  if (!fs::exists(path)) return false;
  try {
    read();
    return true;
  } catch (const InputError& e) {
    LogWarning(std::string("dense: ") + e.what() + "; made again");
    return false;
  }
}

}  // namespace

uint64_t DefaultDenseMemory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  const uint64_t total = pages > 0 && page > 0 ? static_cast<uint64_t>(pages) * page : (8ull << 30);
  return total / 4;
}

void DenseStreamOptions::Check() const {
  stereo.Check();
  fusion.Check();
  CANDI_CHECK_OPTION(ranks >= 1 && rank >= 0 && rank < ranks, rank, "in [0, ranks)");
  CANDI_CHECK(ranks == 1 || all_gather) << "several ranks need all_gather";
}

DenseStreamResult RunDenseStream(const DenseStreamOptions& options, const std::string& workspace) {
  options.Check();
  DenseStreamResult out;
  out.max_memory = options.max_memory > 0 ? options.max_memory : DefaultDenseMemory();
  const int rank = options.rank, ranks = options.ranks;
  const auto mine = [&](int k) { return k % ranks == rank; };
  const std::string who = ranks > 1 ? "dense (rank " + std::to_string(rank) + " of " + std::to_string(ranks) + "): "
                                    : "dense: ";
  const Layout layout(workspace);
  const StereoInput model = ReadDenseModel(workspace);
  const int n = static_cast<int>(model.images.size());
  out.images = n;
  out.sparse_points = model.sparse_points.size();
  out.sources_from_tracks = !model.point_views.empty();
  const PatchMatchOptions& so = options.stereo;
  std::vector<PinholeCamera> cameras;  // at the working resolution
  for (const StereoImage& image : model.images)
    cameras.push_back(so.resolution_scale == 1.0 ? image.camera : image.camera.Scaled(so.resolution_scale));
  const StereoPlan plan = PlanStereo(so, model);
  const std::vector<std::pair<double, double>>& ranges = plan.ranges;
  const std::vector<ViewLinks>& links = plan.links;
  const std::vector<std::vector<int>> neighbours = NeighbourViews(links);

  // Ends a stage on every rank: the first failure anywhere fails every rank, and the ranks' counts
  // (and the photos without depth) are added up.
  std::vector<uint64_t> counts;
  const auto sync = [&](std::exception_ptr failure) {
    if (ranks == 1) {
      if (failure) std::rethrow_exception(failure);
      return;
    }
    std::string mine_text;
    if (failure) {
      try {
        std::rethrow_exception(failure);
      } catch (const std::exception& e) {
        mine_text = std::string("E") + e.what();
      } catch (...) {
        mine_text = "Eunknown failure";
      }
    } else {
      mine_text = "O";
      for (uint64_t c : counts) mine_text += std::to_string(c) + " ";
      for (const std::string& name : out.empty_maps) mine_text += "\n" + name;
    }
    const std::vector<std::string> all = options.all_gather(mine_text);
    if (failure) std::rethrow_exception(failure);
    for (size_t r = 0; r < all.size(); ++r)
      if (all[r].empty() || all[r][0] != 'O')
        throw InputError(workspace, "rank " + std::to_string(r), all[r].empty() ? "failed" : all[r].substr(1));
    std::vector<uint64_t> sums(counts.size(), 0);
    std::vector<std::string> empty;
    for (const std::string& text : all) {
      const size_t line = text.find('\n');
      size_t at = 1;
      for (uint64_t& sum : sums) {
        size_t used = 0;
        sum += std::stoull(text.substr(at), &used);
        at += used + 1;
      }
      for (size_t start = line; start != std::string::npos;) {
        const size_t end = text.find('\n', start + 1);
        empty.push_back(text.substr(start + 1, end == std::string::npos ? std::string::npos : end - start - 1));
        start = end;
      }
    }
    counts = sums;
    std::sort(empty.begin(), empty.end(), [&](const std::string& a, const std::string& b) {
      const auto index = [&](const std::string& name) {
        for (int r = 0; r < n; ++r)
          if (model.images[r].name == name) return r;
        return n;
      };
      return index(a) < index(b);
    });
    out.empty_maps = empty;
  };
  const auto stage = [&](const std::function<void()>& body) {
    std::exception_ptr failure;
    try {
      body();
    } catch (...) {
      failure = std::current_exception();
    }
    sync(failure);
  };

  // The settings and the sources: rank 0 writes them, then every rank goes on.
  counts.assign(1, 0);
  stage([&] {
    if (rank != 0) return;
    counts[0] = ReconcileSettings(layout, model, StageKeys(options, workspace, model));
    std::vector<std::string> names;
    for (const StereoImage& image : model.images) names.push_back(image.name);
    const std::string cfg = (layout.stereo / "patch-match.cfg").string();
    CreateParentFolder(cfg);
    WriteFileAtomic(cfg, PatchMatchConfig(names, links));
  });
  out.settings_changed = counts[0] > 0;

  auto run = [&] {
    // Stereo: each photo against its sources, through the cache.
    Stopwatch watch;
    counts.assign(2, 0);
    stage([&] {
      std::vector<int> todo;
      size_t share = 0;
      for (int r = 0; r < n; ++r) {
        if (!mine(r)) continue;
        ++share;
        const std::string path = layout.Raw(model.images[r].name);
        if (Readable(path, [&] { DepthMapFileValidPixels(path, cameras[r]); }))
          ++counts[0];
        else
          todo.push_back(r);
      }
      if (counts[0] > 0)
        LogInfo(who + std::to_string(counts[0]) + " of " + std::to_string(share) + " depth maps found finished in " +
                (layout.candi / "raw").string() + "; " + std::to_string(todo.size()) + " to make");
      uint64_t total = 0, done = 0;
      for (int r : todo) total += static_cast<uint64_t>(cameras[r].width) * cameras[r].height * (2 * so.iterations + 1);
      ConsoleProgressOptions po;
      po.unit = "pixel sweeps";
      ConsoleProgress progress("dense: stereo", po);
      ViewCache cache(workspace, model, so.resolution_scale, out.max_memory / 2);
      for (int r : todo) {
        const std::shared_ptr<const StereoView> ref = cache.Get(r);
        std::vector<std::shared_ptr<const StereoView>> held;
        std::vector<const StereoView*> src;
        for (int s : links[r].sources) {
          held.push_back(cache.Get(s));
          src.push_back(held.back().get());
        }
        const DepthNormalMap map = MatchReference(so, *ref, r, src, links[r].sources, ranges[r], [&](uint64_t k) {
          done += k;
          progress.Update(done, total);
        });
        WriteDepthMapFile(map, true, layout.Raw(model.images[r].name));
        ++counts[1];
        if (options.committed) options.committed("stereo", counts[0] + counts[1]);
      }
      progress.Finish();
      out.peak_cache_bytes = cache.peak();
    });
    out.maps_found = counts[0];
    out.maps_made = counts[1];
    out.stereo_seconds = watch.Seconds();
    watch.Restart();
    // The filter: each photo's raw map against its neighbours' raw maps.
    counts.assign(3, 0);  // found, valid pixels, pixels
    stage([&] {
      ConsoleProgressOptions po;
      po.unit = "photos";
      ConsoleProgress progress("dense: filter", po);
      size_t made = 0, share = 0, done = 0;
      for (int r = 0; r < n; ++r) share += mine(r);
      for (int r = 0; r < n; ++r) {
        if (!mine(r)) continue;
        const std::string& name = model.images[r].name;
        const std::string path = layout.Filtered(name);
        uint64_t valid = 0;
        if (Readable(path, [&] { valid = DepthMapFileValidPixels(path, cameras[r]); })) {
          ++counts[0];
        } else {
          DepthNormalMap map = ReadDepthMapFile(layout.Raw(name), cameras[r]);
          std::vector<DepthNormalMap> raw;
          raw.reserve(neighbours[r].size());
          for (int s : neighbours[r]) raw.push_back(ReadDepthMapFile(layout.Raw(model.images[s].name), cameras[s]));
          std::vector<const DepthNormalMap*> src;
          for (const DepthNormalMap& m : raw) src.push_back(&m);
          FilterDepthMap(so, src, &map);
          if (options.keep_maps) {
            CreateParentFolder(layout.Colmap("depth_maps", name));
            CreateParentFolder(layout.Colmap("normal_maps", name));
            WriteColmapArray(NormalArray(map), layout.Colmap("normal_maps", name));
            WriteColmapArray(DepthArray(map), layout.Colmap("depth_maps", name));
          }
          WriteDepthMapFile(map, false, path);
          for (float d : map.depth.values()) valid += d > 0;
          ++made;
          if (options.committed) options.committed("filter", counts[0] + made);
        }
        counts[1] += valid;
        counts[2] += static_cast<uint64_t>(cameras[r].width) * cameras[r].height;
        if (valid == 0) {
          out.empty_maps.push_back(name);
          LogWarning(who + name + " has no depth (" +
                     (links[r].sources.empty() ? std::string("no source views: no sparse point in front of it, or none that "
                                                             "another photo shares at a usable angle")
                                         : std::string("textureless, or its sources disagree")) +
                     "); fusion goes on without it");
        }
        progress.Update(++done, share);
      }
      progress.Finish();
      if (counts[0] > 0)
        LogInfo(who + std::to_string(counts[0]) + " of " + std::to_string(share) + " filtered maps found finished");
    });
    out.filtered_found = counts[0];
    out.valid_pixels = counts[1];
    out.total_pixels = counts[2];
    out.filter_seconds = watch.Seconds();
    watch.Restart();
    // Fusion, cell by cell.
    const FusionTiles tiles(model.sparse_points, PointViews(model), options.fusion.max_tile_views);
    out.tiles = tiles.count();
    counts.assign(1, 0);
    const std::vector<std::string> empty_maps = out.empty_maps;
    out.empty_maps.clear();  // added up already
    stage([&] {
      const DiskMaps maps(layout, model, cameras);
      std::vector<int> todo;
      size_t share = 0;
      for (int t = 0; t < tiles.count(); ++t) {
        if (!mine(t)) continue;
        ++share;
        const std::string path = layout.Tile(t);
        if (Readable(path, [&] { TileFilePoints(path); }))
          ++counts[0];
        else
          todo.push_back(t);
      }
      if (counts[0] > 0)
        LogInfo(who + std::to_string(counts[0]) + " of " + std::to_string(share) + " fusion cells found finished");
      if (todo.empty()) return;
      const std::vector<std::vector<int>> tile_views = TileViews(tiles, maps);
      ConsoleProgressOptions po;
      po.unit = "cells";
      ConsoleProgress progress("dense: fusion", po);
      // Cells in waves that fit the budget (a cell's maps: 20 bytes a pixel), parallel within.
      std::mutex mutex;
      size_t made = 0;
      for (size_t begin = 0; begin < todo.size();) {
        size_t end = begin;
        uint64_t bytes = 0;
        while (end < todo.size()) {
          uint64_t cell = 0;
          for (int v : tile_views[todo[end]]) cell += 20ull * cameras[v].width * cameras[v].height;
          if (end > begin && bytes + cell > out.max_memory) break;
          bytes += cell;
          ++end;
        }
        ParallelFor(tbb::blocked_range<size_t>(begin, end, 1), [&](const tbb::blocked_range<size_t>& range) {
          for (size_t k = range.begin(); k < range.end(); ++k) {
            const int t = todo[k];
            WriteTileFile(FuseTile(options.fusion, tiles, t, tile_views[t], neighbours, maps), layout.Tile(t));
            std::lock_guard<std::mutex> lock(mutex);
            ++made;
            progress.Update(made, todo.size());
            if (options.committed) options.committed("fusion", counts[0] + made);
          }
        });
        begin = end;
      }
      progress.Finish();
    });
    out.tiles_found = counts[0];
    out.empty_maps = empty_maps;
    if (rank == 0) {
      out.cloud = FusedCloud();
      for (int t = 0; t < tiles.count(); ++t) {
        if (!options.cells_out) {
          AppendTileFile(layout.Tile(t), &out.cloud);
          continue;
        }
        PointCloud cell = FusedCloud();
        AppendTileFile(layout.Tile(t), &cell);
        out.points += cell.size();
        options.cells_out(cell);
      }
      if (!options.cells_out) out.points = out.cloud.size();
    }
    out.fusion_seconds = watch.Seconds();
  };
  if (so.threads > 0) {
    tbb::task_arena arena(so.threads);
    arena.execute(run);
  } else {
    run();
  }
  if (!options.keep_maps && rank == 0) {
    fs::remove_all(layout.candi);
    fs::remove(layout.stereo / "patch-match.cfg");
  }
  return out;
}

}  // namespace candi::photogrammetry
