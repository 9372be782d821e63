// The two COLMAP model harnesses (fuzz_colmap_bin.cc, fuzz_colmap_text.cc): the input holds
// cameras, images and points3D (in that order) separated by kFuzzPartSeparator; parts the input
// does not reach are absent files.
#pragma once

#include <cstddef>
#include <cstdint>

namespace candi::fuzz {
void FuzzColmapModel(const uint8_t* data, size_t size, const char* extension);
}  // namespace candi::fuzz
