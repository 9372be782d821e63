// candi view, publish: the browser viewer (pipeline/viewer.h: a build directory, an archive or
// point files served until Ctrl-C, under mpirun with every rank drawing a share of each image) and
// the static web site that renders the archive in the visitor's browser (view/publish.h).
#include <cstdio>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/failure.h"
#include "apps/option_groups.h"
#include "core/progress.h"
#include "pipeline/viewer.h"
#include "view/publish.h"
#include "view/server.h"

namespace candi::apps {

namespace {

struct ViewArgs {
  std::vector<std::string> inputs;  // a build directory, an archive, or point files
  pipeline::ViewerOptions options;  // server (host, threads, caps), port, columns, preview
  OrientationArgs orientation;
  ClipArgs clip;                    // the clipping the page starts with
  FieldArgs field;                  // point files: coloured by a field
};

int RunView(const ViewArgs& a) {
  pipeline::ViewerOptions o = a.options;
  o.orientation = ParseOrientation(a.orientation);
  o.colour_by = ParseFieldColouring(a.field);
  o.clip = ParseClip(a.clip);
  ConsoleTasks tasks;
  pipeline::ViewerCallbacks callbacks;
  callbacks.progress = tasks.Callbacks();
  callbacks.serving = [](view::Server& server) {
    std::printf("candi view: %s\n", server.Url().c_str());
    std::fflush(stdout);
  };
  callbacks.describe = DescribeFailureForMpi;
  pipeline::ServeViewer(o, a.inputs, callbacks);
  return kOk;
}

}  // namespace

void AddView(Command& root) {
  ViewArgs& a = root.Keep<ViewArgs>();
  view::ServerOptions& s = a.options.server;
  Command c = root.Add("view", "Open an archive in the browser: orbit it see-through while the server renders "
                               "(SPBR), the image refining as you watch");
  c.Option("inputs", a.inputs, "A build directory (candi build), a render archive (candi pack), or point files "
           "(packed on the fly into a temporary archive)").Required();
  c.Option("--host", s.host, "Address to serve on (default 127.0.0.1; 0.0.0.0 serves your network: anyone "
           "with the printed address and token sees the data)");
  c.Option("--port", a.options.port, "Port (0: any free one)").Range(0, 65535);
  AddOrientation(c, a.orientation,
                 {"World up for the first view, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)",
                  "Direction the first view looks in, x,y,z (default: oblique, from above)",
                  "A COLMAP model (e.g. WORK/sparse/0) whose frame the points are in: the first view's up and side "
                  "from its cameras"});
  c.Option("--columns", a.options.columns, "XYZ/PTS column spec");
  c.Option("--threads", s.threads, "Render threads (0: all)").Range(0, 256);
  c.Option("--max-pages", s.max_clients, "Pages open at once (default 16)");
  c.Option("--max-pixels", s.max_pixels, "Image pixels of all open pages together (16 bytes each; default "
           "33554432: 16 full-HD pages or two of 4096x4096)");
  c.Option("--section-seconds", s.section_seconds, "A section export's time limit, s (default 120)");
  c.Option("--section-max-points", s.section_max_points, "The most points an exported slab may hold "
           "(default 20000000)");
  c.Option("--preview", a.options.preview, "Point files of more than twice this many points (binary PLY, LAS): a preview of "
           "this many is shown first, the whole replacing it once packed (0: none; default 10000000)");
  AddClip(c, a.clip);
  AddFieldColouring(c, a.field);
  c.Run([&a] { return RunView(a); });
  c.Footer("Example: candi view borobudur_out/   (then open the printed http://127.0.0.1:8765/?token=... address)");
}

namespace {

struct PublishArgs {
  std::string input;                // a build directory, a demo's output, or an archive
  std::string output;               // the site's folder
  view::PublishOptions options;
  OrientationArgs orientation;
};

int RunPublish(const PublishArgs& a) {
  a.options.Check();
  ConsoleProgress progress("publish");
  const view::PublishStats s = view::PublishSite(a.options, a.input, a.output,
                                                 ParseOrientation(a.orientation).Resolve(), progress.Callback());
  progress.Finish();
  const double mb = 1e-6;
  std::printf("%s: %llu points in %llu chunks, %llu groups x %d pages = %llu files\n", a.output.c_str(),
              static_cast<unsigned long long>(s.points), static_cast<unsigned long long>(s.chunks),
              static_cast<unsigned long long>(s.groups), s.repeat_level, static_cast<unsigned long long>(s.files));
  std::printf("  data %.1f MB: %.2f bytes a point (the archive: 8; COPC: ~5)\n", s.data_bytes * mb, s.BytesPerPoint());
  std::printf("  before the first image: %.2f MB (the page, site.json and every group's first page)\n",
              s.first_image_bytes * mb);
  std::printf("  site %.1f MB, written in %.2f s (%.1f M points/s)\n", s.site_bytes * mb, s.seconds,
              s.seconds > 0 ? s.points / s.seconds * 1e-6 : 0.0);
  std::printf("  serve it with any static web server, e.g.: python3 -m http.server -d %s 8000\n", a.output.c_str());
  return kOk;
}

}  // namespace

void AddPublish(Command& root) {
  PublishArgs& a = root.Keep<PublishArgs>();
  view::PublishOptions& o = a.options;
  Command c = root.Add("publish", "Write the archive as a static web site that renders it see-through (SPBR) in "
                                  "the visitor's browser with WebGL2: no server-side code, any static host");
  c.Option("input", a.input, "A build directory (candi build), a demo's output, or a render archive (candi pack)")
      .Required();
  c.Option("-o,--output", a.output,
           "The site's folder (created; an earlier site there is updated in place, "
           "keeping every file publish did not write; a link is followed)")
      .Required();
  c.Option("-L,--repeat-level", o.repeat_level, "L of the data's pages and the page's default L (0: the scene's "
           "render setting, else 100)");
  c.Option("--group-points", o.group_points, "Points of consecutive chunks stored together (a file holds about "
           "this / L points)");
  c.Option("--memory-mb", o.memory_mb, "The page's default budget of points held, MB (16 bytes a point; the "
           "visitor can change it)");
  c.Option("--threads", o.threads, "Threads (0: all)");
  AddOrientation(c, a.orientation,
                 {"World up for the first view, x,y,z (default 0,0,1)",
                  "Direction the first view looks in, x,y,z (default: oblique, from above)",
                  "A COLMAP model whose frame the points are in: the first view's up and side from its cameras"});
  c.Run([&a] { return RunPublish(a); });
  c.Footer("Example: candi publish demo_out -o site && python3 -m http.server -d site 8000   (then open "
           "http://127.0.0.1:8000/)");
}

}  // namespace candi::apps
