// The scene file of `candi build`: every layer of a site, how it is digitized, where it goes and
// how it is shown. JSON, version 1; paths are relative to the scene file's folder.
//
// {
//   "candi_scene": 1,                        required
//   "name": "borobudur",                     optional, default: the file's stem
//   "origin": [E, N, H] | "auto",            the scene's one LocalFrame (default "auto": chosen from
//                                            the layers' bounds, see LocalFrame::Auto)
//   "seed": 1,                               every random step (sampling, opacity, SPBR)
//   "crs": "EPSG:32749",                     the scene's coordinate reference system (any string
//                                            PROJ reads). Layers stating another CRS are
//                                            transformed into it with PROJ (before
//                                            world_from_layer); layers stating none are taken to
//                                            be in it, with a warning. Absent: every layer must
//                                            state the same CRS or none (mixing is an error).
//   "render": {"repeat_level": 100, "width": 1024, "height": 768, "background": [r, g, b],
//              "brightness": "auto" | "none" | gain},
//   "copc": {"layers": false,                COPC for Potree, QGIS, CloudCompare (pipeline/copc_export.h):
//            "scene": false},                each layer as layers/<name>.copc.laz, every layer in one
//                                            copc/<name>.copc.laz (default: neither; writing costs time)
//   "views": [{"name": "overview",           one PNG per view: renders/<name>.png
//              "camera": "view.json" | {...},  a view as `candi render --save-view` writes (world
//                                            coordinates); absent: the default view of the data
//              "opaque": false,              true: L = 1, every layer opaque
//              "layers": ["a", "b"],         default: all
//              "focus": false,               true: highlighted layers at focus_opacity, the others
//              "focus_opacity": 0.95,          at dim x their opacity
//              "dim": 0.5,
//              "opacity": {"a": 0.2},        per-view overrides of layer opacities
//              "point_size": 1}],            pixels, [1, 32] (close-ups of sparse layers)
//   "layers": [{
//     "name": "foundation",                  unique; [A-Za-z0-9_-]+ (it names files)
//     "kind": "points" | "foundation" | "relief" | "photogrammetry",
//     "crs": "EPSG:4979",                    the CRS of the layer's coordinates, for files that
//                                            state none (a file stating a different one is an
//                                            error); "scene": already in the scene's CRS (no
//                                            warning)
//     "world_from_layer": {"matrix": [[4 x 4]]} | {"scale": s, "rotation_deg": [rx, ry, rz],
//                          "translation": [x, y, z]}      (R = Rz Ry Rx; default identity)
//     "color": [r, g, b],                    override every point's colour
//     "opacity": 0.5,                        target opacity in (0, 1] (default 1: every point)
//     "highlight": false,
//     "replaces": ["building"],              this layer supersedes those where it has points:
//     "replace_voxel": 0.5,                    their points in the cubes (metres, on the scene frame's grid)
//                                              holding >= 3 of this layer's points are dropped
//                                              (close-range data over a coarse scan)
//     points:         "file": "scan.las", "columns": "x,y,z,r,g,b" (XYZ/PTS only)
//     foundation:     "dxf": "foundation.dxf", "sections": ["A", ...], "samples_per_side": 1000,
//                     "angular_steps": 90, "density": 50 | "count": K, "mode": "auto"|"blend"|"sweep"
//     relief:         "panels": [{"id": "P01", "photo": "p01.png" | "points": "p01.ply",
//                                 "native_resolution": false}],  (true: the network runs at the
//                                 photo's own pixels per metre instead of resampling it to the
//                                 model's: coarser, faster; for panels seen only from afar)
//                     "model": "relief_model.pt" (with photos), "width_m": 2.7,
//                     "placement": "correspondences.csv" (panel ids as in "panels")
//     photogrammetry: "dense": "dense.ply" | "workspace": "ws/" (runs candi dense) |
//                     "images": "photos/" (runs candi sfm, then candi dense),
//                     "targets": "targets.csv" (georeference, candi georef's format),
//                     "targets_crs": "EPSG:4979" (the targets' CRS, e.g. GNSS in WGS 84:
//                     transformed into the scene's "crs" with PROJ before the fit),
//                     "picks": "picks.csv" (the targets picked in the photos, name,image,u,v in
//                     the undistorted images; with images or workspace),
//                     "max_image_size": 1600, "max_features": 4096 (SIFT, images),
//                     "resolution_scale": 1, "iterations": 3
//                     (dense stereo; images or workspace)
//   }],
//   "comparisons": [{                        deviation maps the build writes to compare/<name>.ply
//     "name": "facade_vs_scan",              unique; [A-Za-z0-9_-]+ (it names files)
//     "compared": "close",                   a layer: one distance per point of its built points
//     "reference": "sheet" | "mesh.ply",     a layer's name, or a point file (for c2m a mesh, PLY
//                                            or OBJ) in world coordinates; relative to this file
//     "method": "c2c" | "c2m" | "m3c2",      default c2c (c2m needs a mesh file)
//     "tolerance": 0.01, "bins": 60, "range": 0,     the summary (compare/report.h), m
//     c2c:  "model": "none" | "plane" | "quadric", "model_neighbours": 12
//     c2m:  "unsigned": false
//     m3c2: "normal_scale", "projection_scale", "max_depth", "registration_error" (m),
//           "min_points": 3, "orientation": "+z" | "-z" | "+x" | "-x" | "+y" | "-y" | "out"
//   }]
// }
// Unknown keys, wrong types, missing files and bad values throw InputError naming the scene file
// and the JSON path of the culprit (e.g. "/layers/2/opacity").
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "compare/deviation.h"
#include "compare/report.h"
#include "core/point_cloud.h"
#include "core/spbr_settings.h"
#include "core/transform.h"
#include "pipeline/copc_export.h"
#include "pipeline/foundation.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"
#include "reconstruction/relief/panel_size.h"
#include "render/camera.h"

namespace candi::pipeline {

enum class LayerKind { kPoints, kFoundation, kRelief, kPhotogrammetry };
std::string LayerKindName(LayerKind kind);

struct ReliefPanelSpec {
  std::string id;
  std::string photo;   // absolute; exactly one of photo and points
  std::string points;
  bool native_resolution = false;  // predict at the photo's own pixels per metre (no resampling)
};

// A foundation layer's options where the scene gives none: the sampling at
// kDefaultFoundationDensity points per m^2.
FoundationPointsOptions SceneFoundationDefaults();

struct SceneLayer {
  std::string name;
  LayerKind kind = LayerKind::kPoints;
  Sim3 world_from_layer;
  std::string crs;  // "" (none stated), "scene", or a CRS PROJ reads
  std::optional<Rgb8> color;
  double opacity = 1.0;
  bool highlight = false;
  // points
  std::string file, columns;
  // foundation: its drawing, and candi foundation's options as the scene sets them: "sections"
  // (layers), "samples_per_side" (surface.profile), "angular_steps" and "mode" (surface.revolve),
  // "count" or "density" (sample; kDefaultFoundationDensity when neither). The seed and threads
  // are the build's.
  std::string dxf;
  FoundationPointsOptions foundation = SceneFoundationDefaults();
  // relief
  std::vector<ReliefPanelSpec> panels;
  std::string model, placement;
  double width_m = relief::kPanelWidthM;
  // photogrammetry
  std::string dense, workspace, images, targets, picks;
  std::string targets_crs;  // "" : the targets are in the scene's CRS
  photogrammetry::SfmOptions sfm;            // "max_image_size", "max_features" (images)
  photogrammetry::PatchMatchOptions stereo;  // "resolution_scale", "iterations" (images, workspace)
  // Layers this one supersedes (see the format above).
  std::vector<std::string> replaces;
  double replace_voxel = 0.5;
  std::string key_json;  // the layer's entry, canonical JSON (part of the build's checkpoint key)
  // Every input file of the layer (absolute), for provenance.
  std::vector<std::string> Sources() const;
};

struct SceneView {
  std::string name;
  std::string camera_file;   // absolute, or "" (inline or default)
  std::optional<render::Camera> camera;  // an inline camera (world), or none
  bool opaque = false;
  std::vector<std::string> layers;  // empty: all
  bool focus = false;
  double focus_opacity = 0.95, dim = 0.5;
  std::map<std::string, double> opacity;
  double point_size = 1.0;          // pixels (candi render --point-size)
  std::string key_json;  // the entry, canonical JSON (part of the build's checkpoint key)
};

// A labelled point of the site: shown as a marker by candi view and a published site, which
// fly to its view (a scene view's name, or an inline camera) or, without one, to the point.
struct SceneAnnotation {
  std::string title;                 // 1-200 characters
  std::string text;                  // may be empty
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world (the scene's CRS), m
  std::string view;                  // a scene view's name, or ""
  std::optional<render::Camera> camera;  // an inline camera (world), or none
};

// A deviation map the build writes once the layers are built (compare/deviation.h): the
// compared layer's points (world coordinates, as layers/<name>.ply holds them) against a
// reference layer's, or a file's.
struct SceneComparison {
  std::string name;             // unique among the comparisons; names compare/<name>.ply
  std::string compared;         // a layer's name
  std::string reference_layer;  // a layer's name, or "" (a file: reference_file)
  std::string reference_file;   // absolute: a point file, or for C2M a mesh, in world coordinates
  compare::DeviationOptions deviation;  // threads: set by the build
  compare::SummaryOptions summary;
  std::string key_json;  // the entry, canonical JSON (part of the build's checkpoint key)
};

// A scene's "render" where it gives none: candi render's settings on a white background.
ImageSettings SceneRenderDefaults();

struct Scene {
  std::string path;   // the scene file
  std::string name;
  std::optional<Eigen::Vector3d> origin;  // none: auto
  unsigned long long seed = 1;
  std::string crs;    // "" : none declared
  // "render": what every view draws with (a view sets its own opaque and point size); its seed is
  // the scene's. The background defaults to white.
  ImageSettings render = SceneRenderDefaults();
  CopcOptions copc;   // the COPC files the build writes
  std::vector<SceneView> views;
  std::vector<SceneLayer> layers;
  std::string licence;                        // the archive's licence text, shown by published pages
  std::vector<SceneAnnotation> annotations;
  std::vector<SceneComparison> comparisons;
  std::string text;   // the file's bytes (hashed for provenance)
  // "origin", "render" and "copc" as canonical JSON ("null" when absent): parts of the build's
  // checkpoint keys.
  std::string origin_json = "null", render_json = "null", copc_json = "null";
};

Scene LoadScene(const std::string& path);

// The opacity layer `layer` gets in `view` (focus, dim and overrides applied), in (0, 1].
double ViewOpacity(const SceneView& view, const SceneLayer& layer);

}  // namespace candi::pipeline
