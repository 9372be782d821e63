// Option groups several commands share, each declared once: a helper adds the group's options to
// a command, bound to the arguments it parses into the library's values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "apps/cli.h"
#include "core/clip.h"
#include "core/field_colour.h"
#include "pipeline/view_orientation.h"

namespace candi::apps {

// --clip-box and --clip-plane (render, view, section): the region the points are clipped to.
struct ClipArgs {
  std::string box;
  std::vector<std::string> planes;
};
void AddClip(Command& c, ClipArgs& clip);
// std::invalid_argument naming the option for a malformed box or plane (arg_parse.h's ParseClip).
ClipRegion ParseClip(const ClipArgs& clip);

// --colour-by, --field-range and --field-scale (render, view, pack): points coloured by a
// scalar field.
struct FieldArgs {
  std::string field, range, scale = "auto";
};
void AddFieldColouring(Command& c, FieldArgs& f);
// std::invalid_argument for a bad range or scale, or a range or scale without a field.
FieldColouring ParseFieldColouring(const FieldArgs& f);

// --up, --from and --cameras (render, view, publish): the default view's orientation, in each
// command's words.
struct OrientationArgs {
  std::string up, from, cameras;
};
struct OrientationHelp {
  std::string up, from, cameras;
};
void AddOrientation(Command& c, OrientationArgs& o, const OrientationHelp& help);
// The directions parsed (std::invalid_argument naming the option); the model is read by Resolve().
pipeline::ViewOrientation ParseOrientation(const OrientationArgs& o);

// --copc-memory MB (convert, build, export copc): the memory a COPC file's records may take until
// it is complete, beyond which they are spilled beside it (0: half this machine's).
// CopcMemoryBytes: its bytes; std::invalid_argument for a negative or NaN value.
void AddCopcMemory(Command& c, double& mb);
uint64_t CopcMemoryBytes(double mb);

}  // namespace candi::apps
