// candi relief synth | dataset | train | predict | points | eval | place: the command line of the
// buried-relief path. The commands run in relief_network.cc (candi-relief) and relief_place.cc.
#include "apps/relief.h"

#include "apps/commands.h"

namespace candi::apps {

namespace {

void AddSynth(Command& relief) {
  ReliefSynthArgs& a = relief.Keep<ReliefSynthArgs>();
  relief::SynthOptions& o = a.synth;
  Command c = relief.Add("synth", "Procedural relief panels as old photos with exact depth (NNN_photo.png 8-bit grey, "
                                  "NNN_depth.png 16-bit levels)");
  c.Option("-o,--output", a.output_dir, "Output folder").Required();
  c.Option("--count", a.count, "Panels").Range(1, 100000);
  c.Option("--width", o.width, "Pixels along the panel").Range(32, 16384);
  c.Option("--seed", o.seed, "Random seed of the series");
  c.Option("--width-m", o.width_m, "Panel width, m");
  c.Option("--height-m", o.height_m, "Panel height, m");
  c.Option("--depth-m", o.depth_m, "Relief depth (front plane), m");
  c.FlagOff("--no-shadows", o.photo.shadows, "No cast shadows");
  c.FlagOff("--no-stains", o.photo.stains, "Uniform stone albedo");
  c.FlagOff("--no-blur", o.photo.blur, "No lens blur");
  c.FlagOff("--no-grain", o.photo.grain, "No film grain");
  c.FlagOff("--no-tone", o.photo.tone, "No tone curve");
  c.FlagOff("--no-fading", o.photo.fading, "No fading or vignetting");
  c.Run([&a] { return RunReliefSynth(a); });
  c.Footer("Example: candi relief synth -o panels --count 16 --seed 1");
}

void AddDataset(Command& relief) {
  ReliefDatasetArgs& a = relief.Keep<ReliefDatasetArgs>();
  pipeline::ReliefDatasetOptions& o = a.options;
  Command c = relief.Add("dataset", "Training pairs from scans of visible panels (or from synthetic panels): "
                                    "orthographic render, patches");
  c.Option("inputs", a.inputs, "Scans " CANDI_POINT_FILES_READ ", panel photos (*_photo.png) or folders of them")
      .Required();
  c.Option("-o,--output", a.output_dir, "Output folder (train/, val/, dataset.txt)").Required();
  c.Option("--pixels-per-m", o.raster.pixels_per_m, "Render resolution, pixels per metre");
  c.Option("--patch", o.patches.patch, "Patch side, pixels (multiple of 32)");
  c.Option("--stride", o.patches.stride, "Step between patches, pixels");
  c.Option("--val-fraction", o.val_fraction, "Inputs held out for validation").Range(0.0, 0.9);
  c.Option("--frame", o.raster.frame, "Scans: panel plane by PCA (auto) or the cloud's x-y (panel)")
      .OneOf({"auto", "panel"});
  c.Option("--depth-m", o.raster.depth_m, "Front plane above the wall, m");
  c.Option("--panel-width-m", o.panel_width_m, "Width of photo inputs without recorded resolution, m");
  c.FlagOff("--no-relight", o.raster.relight, "Scans: use the scan's grey, not a raking-light photo");
  c.Option("--seed", o.raster.seed, "Random seed (simulated photos)");
  Arg colmap = c.Option("--colmap", o.colmap, "Real photos: a COLMAP sparse model; the inputs are dense clouds in "
                        "its frame (views/, holdout/: whole pairs with masks)");
  Arg images = c.Option("--images", o.images, "Real photos: the folder of the model's photos");
  colmap.Needs(images);
  images.Needs(colmap);
  c.Option("--holdout", o.holdout, "Real photos: images kept out of training (names or stems, comma-separated)")
      .Delimiter(',');
  c.Option("--holdout-region", o.holdout_region,
           "Real photos: a surface kept out of training and scored in holdout/ (box:x0,y0,z0,x1,y1,z1 or "
           "side:nx,ny,nz,offset, in the model's frame)");
  c.Option("--holdout-margin", o.holdout_margin, "Real photos: pixels around the held-out surface also kept out")
      .Range(0, 64);
  c.Option("--max-side", o.photo_pairs.max_side, "Real photos: longer side of a pair, pixels").Range(32, 16384);
  c.Run([&a] { return RunReliefDataset(a); });
  c.Footer("Examples: candi relief dataset scan.ply panels/ -o data --patch 128\n"
           "          candi relief dataset dense.ply --colmap sparse/ --images photos/ --holdout "
           "100_7105.JPG -o pairs --max-side 512");
}

void AddTrain(Command& relief) {
  ReliefTrainArgs& a = relief.Keep<ReliefTrainArgs>();
  relief::TrainOptions& o = a.train;
  Command c = relief.Add("train", "Train the BTS-style depth network (libtorch, CPU)");
  c.Option("--data", a.data_dirs, "Folder from `candi relief dataset`; repeatable: the folders' pairs are trained "
           "on together (e.g. synthetic panels and photo pairs cut to one patch size)").Required();
  c.Option("-o,--out", a.output, "Model file to write").Required();
  c.Option("--epochs", o.epochs, "Epochs").Range(1, 100000);
  c.Option("--batch", o.batch, "Batch size").Range(1, 4096);
  c.Option("--growth", a.net.growth, "DenseNet growth rate").Range(2, 64);
  c.Option("--blocks", a.blocks, "Dense layers in the 4 blocks, e.g. 4,6,8,6");
  c.Option("--width", a.net.decoder_width, "Decoder width (BTS num_features; multiple of 16)");
  c.Option("--lr", o.learning_rate, "Start learning rate");
  c.Option("--end-lr", o.end_learning_rate, "End learning rate (polynomial decay, power 0.9)");
  c.Option("--max-seconds", o.max_seconds, "Stop after this many seconds (0: no limit)");
  c.Option("--checkpoint", o.checkpoint, "Checkpoint file (default: <out>.ckpt)");
  c.Flag("--resume", o.resume, "Continue from the checkpoint");
  Arg finetune = c.Option("--finetune", a.finetune, "Start from this model's weights with a fresh optimiser (e.g. "
                          "the shipped model on pairs of real photos)");
  for (const char* net : {"--growth", "--blocks", "--width"}) finetune.Excludes(c.Get(net));
  c.Option("--edge-loss", o.edge_weight, "Weight of the edge term (log-depth differences 1, 2, 4 pixels apart; 0: "
           "off)").Range(0.0, 1000.0);
  c.Flag("--relative", a.relative, "Train (or fine-tune into) a relative model: the scale-and-shift-invariant loss; "
         "scored after a least-squares scale and offset; predicts whole images");
  c.Option("--seed", o.seed, "Random seed (weights, order, augmentation)");
  c.Option("--threads", a.threads, "libtorch threads").Range(1, 256);
  c.Run([&a] { return RunReliefTrain(a); });
  c.Footer("Examples: candi relief train --data data --out model.pt --epochs 20\n"
           "          candi relief train --data pairs --finetune examples/relief/relief_model.pt "
           "--out tuned.pt --lr 3e-4 --epochs 4");
}

void AddPredict(Command& relief) {
  ReliefPredictArgs& a = relief.Keep<ReliefPredictArgs>();
  pipeline::PanelDepthOptions& o = a.options;
  Command c = relief.Add("predict", "Depth of a photo of any size (overlapping tiles, blended without seams)");
  c.Option("photo", a.photo, "Photo (PNG, 8/16-bit, grey or colour)").Required();
  c.Option("--model", a.model, "Model file").Required();
  c.Option("-o,--output", a.output, "Depth PNG (8-bit levels, 0 = front plane, 255 = wall)").Required();
  c.Option("--png16", a.output16, "Also write 16-bit depth (levels x 256)");
  c.Option("--width-m", o.width_m, "The panel's width in the photo, m (0: photo is at the model's resolution)");
  c.Option("--tile", o.predict.tiles.tile, "Tile side, pixels (multiple of 32)");
  c.Option("--overlap", o.predict.tiles.overlap, "Tile overlap, pixels");
  c.Option("--threads", o.threads, "libtorch threads").Range(1, 256);
  c.Run([&a] { return RunReliefPredict(a); });
  c.Footer("Example: candi relief predict photo.png --model model.pt -o depth.png");
}

void AddPoints(Command& relief) {
  ReliefPointsArgs& a = relief.Keep<ReliefPointsArgs>();
  Command c = relief.Add("points", "Metric points of a panel from its photo and depth map (panel frame: x along the "
                                   "wall, y up, z out)");
  c.Option("photo", a.photo, "Photo (grey becomes the colour)").Required();
  c.Option("depth", a.depth, "Depth PNG (levels)").Required();
  c.Option("-o,--output", a.output, "Point file " CANDI_POINT_FILES_WRITTEN).Required();
  c.Option("--width-m", a.options.width_m, "Panel width, m");
  c.Option("--height-m", a.options.height_m, "Panel height, m");
  c.Option("--depth-m", a.options.depth_m, "Relief depth: level 0 is this far out of the wall, m");
  c.Run([&a] { return RunReliefPoints(a); });
  c.Footer("Example: candi relief points photo.png depth.png -o panel.ply --width-m 2.7 --height-m 0.92 "
           "--depth-m 0.15");
}

void AddEval(Command& relief) {
  ReliefEvalArgs& a = relief.Keep<ReliefEvalArgs>();
  Command c = relief.Add("eval", "The paper's Table 2 metrics: model, intensity-as-depth, linear SFS and the paper's "
                                 "BTS");
  c.Option("--model", a.models, "Model file, repeatable (without it: the baselines only)");
  c.Option("--panels", a.panels, "Held-out synthetic panels").Range(1, 10000);
  c.Option("--width", a.synth.width, "Their width, pixels").Range(32, 16384);
  c.Option("--seed", a.synth.seed, "Their seed (keep it apart from the training seeds)");
  c.Option("--photo", a.photo, "Or: one photo ...");
  c.Option("--depth", a.depth, "... and its ground-truth depth PNG");
  c.Option("--pairs", a.pairs, "Or: a folder of <name>_photo.png + _depth.png [+ _mask.png] pairs (real photos: "
           "`relief dataset --colmap`), scored as they are (no resampling); repeatable: each folder a held-out "
           "part, scored alone, then the mean over the parts");
  c.Option("--level-per-pixel", a.surface.level_per_pixel, "Normals: one depth level in pixel widths (default: "
           "depth_m/255 over the panel's metres per pixel; 1 for --pairs)");
  c.Option("--normal-step", a.surface.normal_step, "Normals: differences over this many pixels each side (default 1; "
           "4 for --pairs, whose depth is noisy at one pixel)").Range(1, 16);
  c.Option("--edge-jump", a.surface.edge_jump_levels, "Edges: a depth step of more than this many levels")
      .Range(0.001, 255.0);
  c.Option("--edge-tolerance", a.surface.edge_tolerance_px, "Edges: match within this many pixels").Range(0, 16);
  c.Option("--light-azimuth", a.light_azimuth, "SFS light azimuth, degrees (default: from the photo)");
  c.Option("--light-elevation", a.light_elevation, "SFS light elevation, degrees");
  c.Option("--width-m", a.width_m, "Panel width in --photo, m");
  c.Option("--tile", a.predict.tiles.tile, "Tile side, pixels");
  c.Option("--overlap", a.predict.tiles.overlap, "Tile overlap, pixels");
  c.Option("--threads", a.threads, "libtorch threads").Range(1, 256);
  c.Run([&a] { return RunReliefEval(a); });
  c.Footer("Examples: candi relief eval --model examples/relief/relief_model.pt --panels 4\n"
           "          candi relief eval --pairs pairs/holdout --model examples/relief/relief_model.pt "
           "--model tuned.pt\n"
           "          candi relief eval --pairs left/holdout --pairs centre/holdout --pairs right/holdout "
           "--model tuned.pt");
}

void AddPlace(Command& relief) {
  ReliefPlaceArgs& a = relief.Keep<ReliefPlaceArgs>();
  relief::PanelPlacementOptions& o = a.options;
  Command c = relief.Add("place", "Each panel's world_from_panel by a robust rigid or Sim3 fit (Ceres) of its corners "
                                  "/ edge points to documented wall positions; residuals per panel, misfits warned");
  c.Option("correspondences", a.correspondences, "CSV: panel,point,x,y,z,E,N,H[,accuracy]").Required();
  c.Option("-o,--output", a.output, "Placements JSON (world_from_panel, residuals)").Required();
  c.Option("--panels", a.panels, "The panels' point files, named <panel>.ply, or folders of them");
  c.Option("--points-out", a.points_out, "Folder for the panels in world coordinates (double, shifted; with "
           "--panels)");
  c.Flag("--sim3", o.estimate_scale, "Estimate the scale too (default: rigid, the points are metric)");
  c.Choice("--loss", o.loss,
           {{"none", photogrammetry::RobustLoss::kNone}, {"huber", photogrammetry::RobustLoss::kHuber},
            {"cauchy", photogrammetry::RobustLoss::kCauchy}},
           "Robust loss: huber, cauchy or none");
  c.Option("--loss-scale", o.loss_scale, "Robust loss scale, m").Positive();
  c.Option("--accuracy", o.default_accuracy, "Accuracy of positions without one in the CSV, m").Positive();
  c.Option("--tolerance-mm", o.tolerance_mm, "A panel whose RMS residual exceeds this does not fit (a warning)")
      .Positive();
  c.Run([&a] { return RunReliefPlace(a); });
  c.Footer(
      "CSV: one row per point of a panel: panel id, point name (unique per panel), x,y,z in the\n"
      "panel frame of `relief points` (m: x along the wall from the left edge, y up from the bottom\n"
      "edge, z out of the wall; the corners of a W x H panel are (0,0,0), (W,0,0), (W,H,0), (0,H,0)),\n"
      "E,N,H its documented position on the wall (m), optional accuracy (m). >= 3 points per panel.\n"
      "Exit 0 also when panels do not fit (status 'misfit' or 'collinear' in the table and JSON,\n"
      "a warning each); exit 2 for bad input (file, line and field named), nothing written.\n"
      "Example: candi relief place walls.csv -o placements.json --panels panels/ --points-out world/");
}

}  // namespace

void AddReliefCommands(Command& root) {
  Command relief = root.Add("relief", "Buried reliefs from one old photo: synth, dataset, train, predict, points, "
                                      "eval, place");
  relief.RequireSubcommand();
  AddSynth(relief);
  AddDataset(relief);
  AddTrain(relief);
  AddPredict(relief);
  AddPoints(relief);
  AddEval(relief);
  AddPlace(relief);
}

}  // namespace candi::apps
