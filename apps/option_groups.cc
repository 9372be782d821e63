#include "apps/option_groups.h"

#include <stdexcept>

#include "apps/arg_parse.h"
#include "core/text_format.h"

namespace candi::apps {

void AddClip(Command& c, ClipArgs& clip) {
  c.Option("--clip-box", clip.box, "Keep only points inside this box, world (survey) coordinates: "
           "xmin,ymin,zmin,xmax,ymax,zmax");
  c.Option("--clip-plane", clip.planes, "Keep only the side of a plane its normal points into: px,py,pz,nx,ny,nz "
           "(world coordinates; repeat for several)").Repeatable();
}

ClipRegion ParseClip(const ClipArgs& clip) { return ParseClip(clip.box, clip.planes); }

void AddFieldColouring(Command& c, FieldArgs& f) {
  c.Option("--colour-by", f.field, "Colour the points by a scalar field (e.g. distance from candi compare, "
           "intensity, classification; elevation: world z), with a legend of the scale");
  c.Option("--field-range", f.range, "With --colour-by: the range lo,hi of the scale; values outside are grey "
           "(default: from the values' 2nd-98th percentiles, symmetric about 0 on a diverging scale)");
  c.Option("--field-scale", f.scale, "With --colour-by: auto, diverging (signed, e.g. deviations), sequential or "
           "classes (LAS classes)");
}

FieldColouring ParseFieldColouring(const FieldArgs& f) {
  FieldColouring c;
  if (f.field.empty()) {
    if (!f.range.empty() || f.scale != "auto") throw std::invalid_argument("--field-range and --field-scale need --colour-by");
    return c;
  }
  c.field = f.field;
  c.scale = ParseFieldScale(f.scale);
  if (!f.range.empty()) {
    const std::vector<double> v = ParseNumbers(f.range, ',', "--field-range");
    if (v.size() != 2) throw std::invalid_argument("--field-range '" + f.range + "': expected lo,hi");
    c.lo = v[0];
    c.hi = v[1];
  }
  c.Check();
  return c;
}

void AddOrientation(Command& c, OrientationArgs& o, const OrientationHelp& help) {
  c.Option("--up", o.up, help.up);
  c.Option("--from", o.from, help.from);
  c.Option("--cameras", o.cameras, help.cameras);
}

pipeline::ViewOrientation ParseOrientation(const OrientationArgs& o) {
  pipeline::ViewOrientation v;
  v.cameras = o.cameras;
  if (!o.up.empty()) v.up = ParseDirection(o.up, "--up");
  if (!o.from.empty()) v.view_dir = ParseDirection(o.from, "--from");
  return v;
}

void AddCopcMemory(Command& c, double& mb) {
  c.Option("--copc-memory", mb,
           "COPC output: the memory (MB) its records may take until the file is complete; "
           "beyond it they are spilled beside the file (default 0: half of this machine's)");
}

uint64_t CopcMemoryBytes(double mb) {
  if (!(mb >= 0)) {
    throw std::invalid_argument("--copc-memory " + FormatSignificant(mb, 6) +
                                ": must be >= 0 (MB; 0: half of this machine's memory)");
  }
  return static_cast<uint64_t>(mb * 1048576.0);
}

}  // namespace candi::apps
