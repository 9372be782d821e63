// GPS time coding shared by LASzip's GPSTIME11 v2 (pointwise) and POINT14 v3 (layered) items:
// up to four interleaved time sequences, each with its last time and the last integer difference
// of the float64 bit patterns; a time is coded as a difference predicted from a multiple of that
// last difference, as a switch to another sequence, or as the start of a new one (the upper 32
// bits predicted, the lower 32 raw).
//
// Internal to io/laz. The encoder mirrors the items' decoders (laz_pointwise.cc, laz_layered.cc)
// and LASzip's writers, including the float32 quantisation of the multiplier. Not thread-safe.
#pragma once

#include <array>
#include <cstdint>

#include "io/laz/laz_arith.h"

namespace candi::io::laz {

// GPS time prediction state (LASzip "multi-sequence").
struct GpsSequences {
  uint32_t last = 0, next = 0;
  std::array<uint64_t, 4> time{};  // the doubles' bit patterns
  std::array<int32_t, 4> diff{};
  std::array<int32_t, 4> extreme_count{};
};

// The models one item codes its times with. `unchanged_codes`: GPSTIME11 v2 codes an unchanged
// time too (symbol 0 of zero_diff, 511 of multi) and so numbers its other codes one higher;
// POINT14 v3 codes only changed times.
struct GpsTimeModels {
  SymbolModel* zero_diff = nullptr;  // used while the sequence's last difference is 0
  SymbolModel* multi = nullptr;      // used otherwise
  IntegerCoder* ic = nullptr;        // IntegerCoder(32, 9)
  bool unchanged_codes = false;
};

// Codes the time `time` (a float64's bits) into `encoder` and updates `sequences`.
void EncodeGpsTime(ArithmeticEncoder* encoder, const GpsTimeModels& models, uint64_t time,
                   GpsSequences* sequences);

}  // namespace candi::io::laz
