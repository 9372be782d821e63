// From a section drawing to one layer's surface mesh (ALGORITHMS.md §2): the section pieces of a
// layer are joined (mesh/cad_section.h), split and resampled (mesh/profile.h), blended or swept
// (mesh/revolve.h), meshed in OpenMesh (mesh/surface_mesh.h) and checked with CGAL
// (mesh/mesh_check.h).
// Failures: InputError naming the file and layer (a missing layer lists the drawing's layers).
// Thread-safe (pure function of its arguments).
#pragma once

#include <string>
#include <vector>

#include "core/tri_mesh.h"
#include "mesh/cad_section.h"
#include "mesh/dxf_import.h"
#include "mesh/mesh_check.h"
#include "mesh/profile.h"
#include "mesh/revolve.h"
#include "mesh/surface_mesh.h"

namespace candi::mesh {

struct FoundationOptions {
  DxfReadOptions dxf;
  SectionOptions section;
  ProfileOptions profile;
  RevolveOptions revolve;
  SurfaceMeshOptions mesh;
  bool check = true;  // run the CGAL checks
  MeshCheckOptions check_options;
  void Check() const;  // each part's Check()
};

struct LayerSurface {
  std::string layer;
  Profile profile;
  RevolveMode mode = RevolveMode::kBlend;  // the mode used
  double asymmetry = 0;                    // see SurfaceGrid::asymmetry
  TriMesh mesh;                            // local frame (mesh.vertices.frame)
  bool checked = false;
  MeshCheckReport check;
};

// The layer's section pieces joined into one polyline; InputError when the layer is absent.
Polyline2 LayerSection(const FoundationOptions& options, const DxfDrawing& drawing,
                       const std::string& layer);

LayerSurface BuildLayerSurface(const FoundationOptions& options, const DxfDrawing& drawing,
                               const std::string& layer);

// Every named layer, built concurrently on up to `threads` threads (0 = hardware concurrency);
// results in the order of `layers`. The first failing layer's exception (in that order) is
// rethrown.
std::vector<LayerSurface> BuildLayerSurfaces(const FoundationOptions& options,
                                             const DxfDrawing& drawing,
                                             const std::vector<std::string>& layers,
                                             int threads = 0);

}  // namespace candi::mesh
