// `candi publish`: the archive as a static web site that renders SPBR in the visitor's browser
// (WebGL2), with nothing running on a server.
//
// The site (docs/guide/publish.md):
//   SITE/index.html, viewer.css, controls.js and the modules it wires (the page's controls,
//        shared with candi view), site.js (the entry: the WebGL2 renderer site_gl.js and
//        site_view.js, the loader site_loader.js, picking site_pick.js), site_index.js
//        (site.json checked before use), site_worker.js (decoding, off the main thread)
//   SITE/site.json   the page's scene (ViewerSource::ToJson) and the data's index (below)
//   SITE/data/<group>/<page>.bin
// The data: the archive's chunks, grouped in runs of consecutive chunks (at most group_points
// points a group), each group cut into L pages: page k of a group holds, for each of its chunks
// in order, the chunk's slice that ensemble k draws at repeat level L and the page's seed
// (render/archive.h, EnsembleSlices). So the first image, ensemble 0, needs page 0 of every
// group and nothing else, and a static server without HTTP Range support serves it. A page file
// is the archive's 8-byte points (colour and the 40 quantized position bits, unchanged), stored
// as 8 byte planes (byte j of every point, then byte j + 1; the colours' planes compress) and
// gzip-compressed (the browser's DecompressionStream decodes it). Files are named and listed in
// site.json with their sizes and point counts, so the page names any file that is missing,
// short or damaged (gzip's CRC-32), and draws the rest.
#pragma once

#include <cstdint>
#include <string>

#include "core/progress.h"
#include "render/first_view.h"

namespace candi::view {

inline constexpr int kSiteVersion = 1;
inline constexpr const char* kSiteIndex = "site.json";

struct PublishOptions {
  // L of the pages (and the page's default L): 0 takes the source's (a build's scene render
  // setting, else candi view's 100). In [0, 1000].
  int repeat_level = 0;
  // Points of consecutive chunks a group's files hold together, in [1, 2^28]: a page file holds
  // about group_points / L points (fewer, larger files with more).
  uint64_t group_points = uint64_t{1} << 21;
  // The page's default budget of points held (decoded, on the CPU and the GPU: 16 bytes a point),
  // in MB; the visitor may change it. In [16, 65536]. 128 MB (8 M points) suits a phone.
  int memory_mb = 128;
  int threads = 0;      // 0: as TBB allows
  void Check() const;
};

struct PublishStats {
  uint64_t points = 0, chunks = 0, groups = 0, files = 0;
  uint64_t data_bytes = 0;         // every data file
  uint64_t first_image_bytes = 0;  // site.json, the page's files and every group's page 0
  uint64_t site_bytes = 0;         // everything
  int repeat_level = 0;
  double seconds = 0;
  double BytesPerPoint() const { return points ? static_cast<double>(data_bytes) / static_cast<double>(points) : 0; }
};

// True when `path` is a folder holding a site.json written by candi publish.
bool IsSite(const std::string& path);

// Publishes `input` (a build directory, a demo's output holding one, or a render archive) as a
// site in `site_dir`, a symbolic link followed to the folder it names. A new folder is built
// beside its place and renamed into it. A folder holding an earlier site (or an empty one) is
// updated in place: the new site is built in a folder inside it, then each of its files is
// renamed over the old one (atomic per file) and data/ is exchanged whole; everything publish does
// not write (.git, CNAME, .nojekyll, any other file or folder) is kept. Refused with InputError
// naming the path: a folder that holds something else, a file where the site's own file goes,
// files in data/ that the earlier site.json does not list, a link to nothing. `orientation`
// orients the first view as in candi view.
PublishStats PublishSite(const PublishOptions& options, const std::string& input, const std::string& site_dir,
                         const render::Orientation& orientation, const ProgressCallback& progress = nullptr);

}  // namespace candi::view
