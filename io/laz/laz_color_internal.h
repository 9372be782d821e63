// The colour coding shared by LASzip's RGB12 v2 (pointwise) and RGB14/RGBNIR14 v3 (layered)
// items: a byte-used mask, then per changed byte a correction of the last value; green and blue
// are predicted from red's change, and a grey colour codes red only. NIR codes its two bytes
// against the last NIR.
//
// Internal to io/laz; the items' decoders and encoders call these, one per point, with the
// last colour of their context. Not thread-safe (the models adapt).
#pragma once

#include <cstdint>
#include <vector>

#include "io/laz/laz_arith.h"

namespace candi::io::laz {

struct RgbModels {
  SymbolModel byte_used{128};
  std::vector<SymbolModel> diff = std::vector<SymbolModel>(6, SymbolModel(256));
};
struct NirModels {
  SymbolModel byte_used{4};
  std::vector<SymbolModel> diff = std::vector<SymbolModel>(2, SymbolModel(256));
};

// rgb, last: red, green, blue (distinct arrays). EncodeRgb returns the byte-used symbol (0: the
// colour is grey and equal to `last`).
void DecodeRgb(ArithmeticDecoder* decoder, RgbModels* models, const uint16_t* last, uint16_t* rgb);
uint32_t EncodeRgb(ArithmeticEncoder* encoder, RgbModels* models, const uint16_t* last,
                   const uint16_t* rgb);
uint16_t DecodeNir(ArithmeticDecoder* decoder, NirModels* models, uint16_t last);
void EncodeNir(ArithmeticEncoder* encoder, NirModels* models, uint16_t last, uint16_t nir);

}  // namespace candi::io::laz
