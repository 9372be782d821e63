// `candi view`: a build directory, a render archive or point files served to the browser
// (view/server.h) until the server stops, under mpirun with every rank drawing a share of each
// image (render/mpi/archive_ranks.h).
//
// Point files are packed into a temporary archive (removed when ServeViewer returns, and by an
// interrupt). Files of more than twice `preview` points whose points are records show a preview
// first (view::PackPreviewSource) while a thread packs every point, which then replaces it for
// every page (view::Server::Replace). A page's section export is answered by
// ExportViewerSection (pipeline/section.h) from the archive shown. Under mpirun rank 0 opens the
// source and serves, the other ranks draw their shares of its requests, and there is no preview.
// World (survey) coordinates. Failures: std::invalid_argument for invalid options and inputs (a
// directory among several inputs, an archive to colour by a field), InputError for inputs that
// cannot be read and a port that cannot be bound; the packing thread's error, once the server
// has stopped. One viewer per process (MPI and the interrupt's temporaries are the process's).
// Library candi_pipeline_mpi (MPI), linked only by the command line.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/clip.h"
#include "core/field_colour.h"
#include "core/task_progress.h"
#include "pipeline/view_orientation.h"
#include "render/mpi/archive_ranks.h"
#include "view/server.h"

namespace candi::pipeline {

// The viewer's usual port: given it, the viewer takes the first of it and the 19 after it that
// is free (as Jupyter does); another port is taken as given.
inline constexpr int kViewerPort = 8765;

struct ViewerOptions {
  view::ServerOptions server;  // host, render threads, the caps (port and log: set by ServeViewer)
  int port = kViewerPort;      // [0, 65535]; 0: any free port
  std::string columns;         // XYZ/PTS column spec of point files
  // Point files of more than twice this many points whose points are records: a preview of this
  // many is shown first, the whole replacing it once packed; 0: none.
  uint64_t preview = 10000000;
  ViewOrientation orientation;  // the first view of inputs that save none (rank 0 reads a model)
  ClipRegion clip;              // the clipping the page starts with (world)
  FieldColouring colour_by;     // point files coloured by a scalar field
  void Check() const;
};

struct ViewerCallbacks {
  TaskProgress progress;  // the packing of point files (a preview's, then the whole's on a thread)
  // The server is listening (rank 0), before it serves: its address is server.Url(). The
  // server stops when Stop() is called (from any thread) or the whole packing fails.
  std::function<void(view::Server& server)> serving;
  // A rank's failure as its exit code and one line (under mpirun; apps/failure.h).
  render::mpi::FailureDescriber describe;
};

// Serves `inputs` (a build directory or an archive alone, or point files) until the server
// stops; without mpirun that is when the process is interrupted, or Stop() is called.
void ServeViewer(const ViewerOptions& options, const std::vector<std::string>& inputs,
                 const ViewerCallbacks& callbacks);

}  // namespace candi::pipeline
