// A build's record, `archive.json` (pipeline/build.h writes it; candi view, publish, render and
// export read it): read and written through BuildRecord alone, as the render archive's manifest
// is through ArchiveManifest. It records what the build made (layers, views, comparisons, COPC
// files), from what (sources and their SHA-256, the scene file's hash), and the render settings
// the build resolved (L, seed, image size, background, brightness), so that a build folder copied
// to another machine opens with them: nothing here is a path the readers depend on (the scene
// file's path is provenance only; every file of the build is named relative to the record).
//
// The JSON (docs/reference/archive-format.md) keeps its keys sorted and the types each field has
// always had, so a record read and written again gives the same bytes. Free-form parts a stage
// records of itself (a layer's "parameters" and "crs") are kept as their JSON text.
// Records written before the "render" block existed (candi before 2026-12-07) read with
// `render` empty. Failures: InputError naming the file and the JSON path.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/point_cloud.h"
#include "core/spbr_settings.h"
#include "render/camera.h"

namespace candi::render {

inline constexpr const char* kBuildRecord = "archive.json";

struct BuildSourceRecord {
  std::string path;    // as the scene named it (absolute), provenance only
  std::string sha256;  // of the file's bytes
  uint64_t bytes = 0;
};

struct BuildLayerRecord {
  std::string name;
  std::string kind;                    // "points", "foundation", "relief", "photogrammetry"
  bool scanned = false;                // measured (points, photogrammetry), not reconstructed
  std::string method;                  // in words
  std::string parameters_json = "{}";  // the stage's parameters (JSON object)
  std::vector<BuildSourceRecord> sources;
  Eigen::Matrix4d world_from_layer = Eigen::Matrix4d::Identity();
  double opacity = 1;
  bool highlight = false;
  uint64_t points = 0;  // after replacement
  uint64_t dropped_nan = 0;
  std::vector<std::string> replaces;
  std::vector<std::pair<std::string, uint64_t>> replaced_by;  // layer -> points it took, by name
  std::string crs_json = "null";  // what the build did with the layer's CRS (JSON)
  std::string file;               // "layers/<name>.ply", relative to the record
  bool resumed = false;
};

struct BuildViewRecord {
  std::string name;
  std::string png;  // "renders/<name>.png"; its camera is renders/<name>.view.json
  bool opaque = false;
  std::vector<std::pair<std::string, double>> opacity;  // per drawn layer (by name); empty: opaque
  bool resumed = false;
};

struct BuildAnnotationRecord {
  std::string title, text;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world
  std::string view;                                    // a view's name, or ""
  std::optional<Camera> camera;                        // an inline camera (world), or none
};

struct BuildComparisonRecord {
  std::string name, compared;
  std::string reference;  // a layer's name or the reference file
  bool reference_is_layer = false;
  std::string method;  // "c2c", "c2m", "m3c2"
  bool is_signed = false;
  uint64_t count = 0, defined = 0, undefined = 0;
  double mean = 0, std = 0, rms = 0, mean_abs = 0;  // m; NaN when undefined (JSON null)
  double tolerance = 0;                             // m
  double within_tolerance = 0;                      // share of the defined; NaN when none
  std::optional<uint64_t> significant;              // M3C2: distances beyond their LoD95
  bool resumed = false;
};

struct BuildCopcFileRecord {
  std::string path;  // relative to the record
  uint64_t points = 0, bytes = 0;
  std::string layer;  // the layer's name; "" for the scene's file
};

struct BuildCopcRecord {
  std::vector<BuildCopcFileRecord> layers;
  std::optional<BuildCopcFileRecord> scene;
  double scale_m = 0;
  bool resumed = false;
};

struct BuildRecord {
  std::string candi_version;
  std::string scene_path, scene_sha256;  // the scene file (provenance)
  std::string name;
  uint64_t seed = 1;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the scene's frame: world = local + origin
  std::string crs_definition, crs_label;             // "" when none
  uint64_t points = 0;
  std::vector<BuildLayerRecord> layers;
  bool pack_resumed = false;
  std::vector<BuildViewRecord> views;
  // The render settings the build resolved from its scene: what its views drew with (a view adds
  // its own opaque and point size) and what a page opening the build starts with. None in the
  // records of older builds.
  std::optional<ImageSettings> render;
  std::string licence;  // "" when the scene gives none
  std::vector<BuildAnnotationRecord> annotations;
  std::vector<BuildComparisonRecord> comparisons;
  std::optional<BuildCopcRecord> copc;

  // The record's JSON text (two-space indent, keys sorted, a final newline).
  std::string ToJson() const;
  // Parses a record; `path` names it in errors.
  static BuildRecord FromJson(const std::string& text, const std::string& path);
};

// One comparison's entry as archive.json lists it, without "resumed" (JSON object text), and
// back: a build keeps it in its checkpoint to resume from.
std::string ComparisonToJson(const BuildComparisonRecord& c);
BuildComparisonRecord ComparisonFromJson(const std::string& text, const std::string& path);

// A COPC record's files ({"layers": [...], "scene": {...}}: what a build keeps in its checkpoint),
// and back.
std::string CopcFilesToJson(const BuildCopcRecord& copc);
BuildCopcRecord CopcFilesFromJson(const std::string& text, const std::string& path);

// The build folder `path` names: `path` itself or `path`/archive (a demo's output) when it holds
// archive.json beside a render archive in archive/; "" otherwise.
std::string FindBuild(const std::string& path);

// Reads `build_dir`/archive.json (InputError naming the file when missing or malformed).
BuildRecord ReadBuildRecord(const std::string& build_dir);
// Writes it there atomically.
void WriteBuildRecord(const std::string& build_dir, const BuildRecord& record);

}  // namespace candi::render
