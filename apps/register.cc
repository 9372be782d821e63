// candi register, candi register-scans, candi clean: their command lines, in every executable
// (--help); they run in candi-pcl and candi-relief (register_run.cc: PCL). ICP refinement of one
// scan onto another and many scans into one frame at once (pipeline/scan_registration.h);
// statistical outlier removal and voxel thinning (photogrammetry/registration/cleaning.h).
#include "apps/commands.h"

namespace candi::apps {

namespace {
namespace pg = candi::photogrammetry;
}  // namespace

void AddRegister(Command& root) {
  RegisterArgs& a = root.Keep<RegisterArgs>();
  pg::RegistrationOptions& o = a.options.icp;
  Command c = root.Add("register", "ICP refinement of MOVING onto FIXED (PCL, local coordinates): RMS, overlap, the "
                                   "4x4 transform; writes MOVING moved");
  c.Option("moving", a.moving, "Point file to move").Required();
  c.Option("fixed", a.fixed, "Point file to register onto").Required();
  c.Option("-o,--output", a.output, "MOVING after the transform (its precision and shift kept)").Required();
  c.Option("--max-distance", o.max_correspondence_distance, "Largest correspondence distance, m");
  c.Option("--iterations", o.max_iterations, "Largest number of ICP iterations");
  c.Choice("--method", o.method,
           {{"point", pg::IcpMethod::kPointToPoint}, {"plane", pg::IcpMethod::kPointToPlane}},
           "point (point-to-point) or plane (point-to-plane; normals estimated when FIXED has none)");
  c.Option("--voxel", o.voxel, "Thin both clouds to this voxel size for the solve, m");
  c.Option("--transform-out", a.options.transform_out, "Write the transform and figures as JSON");
  c.Option("--initial", a.options.initial, "Initial transform (JSON as --transform-out writes)");
  c.Run([&a] { return RunRegister(a); });
  c.Footer("Example: candi register scan2.las scan1.las -o scan2_reg.las --max-distance 0.2 --transform-out t.json");
}

void AddRegisterScans(Command& root) {
  RegisterScansArgs& a = root.Keep<RegisterScansArgs>();
  pipeline::RegisterScansOptions& s = a.options;
  pg::MultiRegistrationOptions& o = s.registration;
  Command c = root.Add("register-scans", "Many scans into one frame at once: overlapping pairs by point-to-plane ICP, "
                                         "then all poses in one robust Ceres solve (loops close), with control targets");
  c.Option("scans", a.scans, "Point files, one scan each (an E57 file with several scans counts as several, each "
           "starting from its stored pose)").Required();
  c.Option("-o,--output", a.output_dir, "Folder for the moved scans and registration.json").Required();
  c.Option("--poses", s.poses, "Start poses: JSON, a 4x4 world_from_scan per scan (or a registration.json); "
           "default identity");
  c.Flag("--coarse", s.coarse, "Scans without a start pose are first aligned onto scan 0 by FPFH features and "
         "RANSAC (PCL)");
  c.Option("--targets", s.targets, "Targets seen in the scans, CSV: name,scan,x,y,z,E,N,H[,role[,accuracy]] (scan: "
           "index or file name; role control or check)");
  c.Option("--fixed", s.fixed, "Scans held at their start pose, e.g. 0,2 (default: scan 0, or none with 3+ "
           "control targets)");
  c.Option("--max-distance", o.max_correspondence_distance, "Coarse ICP pairing distance, m");
  c.Option("--solve-distance", o.solve_distance, "Fine ICP and global solve pairing distance, m");
  c.Option("--iterations", o.icp_iterations, "ICP iterations per stage");
  c.Option("--voxel", o.voxel, "Thin every scan to this voxel first, m (0: off)");
  c.Option("--icp-voxel", o.icp_voxel, "Thin the moving scan of a pair further for ICP, m (0: off)");
  c.Option("--min-overlap", o.min_overlap, "Overlap a pair needs to count (share of points within the solve distance)");
  c.Option("--loss-scale", o.loss_scale, "Huber scale of the global solve's point-to-plane terms, m");
  c.Option("--rounds", o.outer_iterations, "Global solve rounds (correspondences re-found each)");
  c.Option("--correspondences", o.correspondences_per_pair, "Correspondences per pair and direction");
  c.Option("--coarse-voxel", s.coarse_options.voxel, "With --coarse: thin both scans to this for the features, m");
  c.Option("--coarse-radius", s.coarse_options.feature_radius, "With --coarse: the FPFH features' support radius, m "
           "(> the coarse voxel)");
  c.Option("--coarse-inlier-distance", s.coarse_options.inlier_distance, "With --coarse: a moved point within this "
           "of the other scan is an inlier, m");
  c.Option("--coarse-min-inliers", s.coarse_options.min_inlier_fraction, "With --coarse: the share of inliers a pose "
           "needs, [0, 1] (lower only for scans sharing less than half their points)");
  c.Option("--coarse-iterations", s.coarse_options.max_iterations, "With --coarse: RANSAC iterations");
  c.Option("--seed", s.coarse_options.seed, "With --coarse: the seed of RANSAC's sampling");
  c.Option("--format", s.format, "Extension of the moved scans (ply, las, laz, copc.laz, e57, xyz; default: each scan's own)");
  c.Run([&a] { return RunRegisterScans(a); });
  c.Footer("Example: candi register-scans st1.las st2.las st3.las st4.las -o registered --targets targets.csv\n"
           "         (then candi compare registered/st1.las registered/st2.las -o overlap.las --method m3c2)");
}

void AddClean(Command& root) {
  CleanArgs& a = root.Keep<CleanArgs>();
  pg::CleanOptions& o = a.clean;
  Command c = root.Add("clean", "Statistical outlier removal (PCL) and voxel thinning (one real point per voxel); "
                                "every field kept");
  c.Option("input", a.input, "Input point file").Required();
  c.Option("-o,--output", a.output, "Output point file").Required();
  c.Option("--sor-k", o.sor_neighbours, "Outlier removal: neighbours averaged");
  c.Option("--sor-std", o.sor_std_multiplier, "Outlier removal: threshold in standard deviations");
  c.FlagOff("--no-sor", o.sor, "Skip outlier removal");
  c.Option("--voxel", o.voxel, "Keep the point nearest each voxel's centre, voxel side m");
  c.Run([&a] { return RunClean(a); });
  c.Footer("Example: candi clean dense.ply -o dense_clean.ply --voxel 0.01");
}

}  // namespace candi::apps
