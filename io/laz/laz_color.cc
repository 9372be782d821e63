#include "io/laz/laz_color_internal.h"

namespace candi::io::laz {

namespace {

uint32_t Clamp8(int32_t v) { return v <= 0 ? 0 : v >= 255 ? 255 : static_cast<uint32_t>(v); }
int32_t Lo(uint16_t v) { return v & 255; }
int32_t Hi(uint16_t v) { return v >> 8; }

}  // namespace

void DecodeRgb(ArithmeticDecoder* dec, RgbModels* m, const uint16_t* last, uint16_t* rgb) {
  const uint32_t sym = dec->DecodeSymbol(&m->byte_used);
  auto corr = [&](int i) { return dec->DecodeSymbol(&m->diff[i]); };
  uint32_t r_lo = Lo(last[0]), r_hi = Hi(last[0]);
  if (sym & 1) r_lo = (corr(0) + r_lo) & 255;
  if (sym & 2) r_hi = (corr(1) + r_hi) & 255;
  rgb[0] = static_cast<uint16_t>(r_hi << 8 | r_lo);
  if (!(sym & 64)) {  // grey
    rgb[1] = rgb[2] = rgb[0];
    return;
  }
  const int32_t g_last_lo = Lo(last[1]), b_last_lo = Lo(last[2]);
  const int32_t g_last_hi = Hi(last[1]), b_last_hi = Hi(last[2]);
  int32_t diff = static_cast<int32_t>(r_lo) - Lo(last[0]);
  uint32_t g_lo = g_last_lo, b_lo = b_last_lo, g_hi = g_last_hi, b_hi = b_last_hi;
  if (sym & 4) g_lo = (corr(2) + Clamp8(diff + g_last_lo)) & 255;
  if (sym & 16) {
    const uint32_t c = corr(4);
    diff = (diff + (static_cast<int32_t>(g_lo) - g_last_lo)) / 2;
    b_lo = (c + Clamp8(diff + b_last_lo)) & 255;
  }
  diff = static_cast<int32_t>(r_hi) - Hi(last[0]);
  if (sym & 8) g_hi = (corr(3) + Clamp8(diff + g_last_hi)) & 255;
  if (sym & 32) {
    const uint32_t c = corr(5);
    diff = (diff + (static_cast<int32_t>(g_hi) - g_last_hi)) / 2;
    b_hi = (c + Clamp8(diff + b_last_hi)) & 255;
  }
  rgb[1] = static_cast<uint16_t>(g_hi << 8 | g_lo);
  rgb[2] = static_cast<uint16_t>(b_hi << 8 | b_lo);
}

uint32_t EncodeRgb(ArithmeticEncoder* enc, RgbModels* m, const uint16_t* last,
                   const uint16_t* rgb) {
  uint32_t sym = 0;
  for (int c = 0; c < 3; ++c) {
    sym |= (Lo(last[c]) != Lo(rgb[c]) ? 1u : 0u) << (2 * c);
    sym |= (Hi(last[c]) != Hi(rgb[c]) ? 1u : 0u) << (2 * c + 1);
  }
  if (Lo(rgb[0]) != Lo(rgb[1]) || Lo(rgb[0]) != Lo(rgb[2]) || Hi(rgb[0]) != Hi(rgb[1]) ||
      Hi(rgb[0]) != Hi(rgb[2])) {
    sym |= 64;  // not grey
  }
  enc->EncodeSymbol(&m->byte_used, sym);
  auto corr = [&](int i, int32_t c) { enc->EncodeSymbol(&m->diff[i], static_cast<uint8_t>(c)); };
  // The corrections DecodeRgb adds, in its order.
  const int32_t diff_lo = Lo(rgb[0]) - Lo(last[0]), diff_hi = Hi(rgb[0]) - Hi(last[0]);
  if (sym & 1) corr(0, diff_lo);
  if (sym & 2) corr(1, diff_hi);
  if (!(sym & 64)) return sym;
  if (sym & 4) corr(2, Lo(rgb[1]) - static_cast<int32_t>(Clamp8(diff_lo + Lo(last[1]))));
  if (sym & 16) {
    const int32_t d = (diff_lo + Lo(rgb[1]) - Lo(last[1])) / 2;
    corr(4, Lo(rgb[2]) - static_cast<int32_t>(Clamp8(d + Lo(last[2]))));
  }
  if (sym & 8) corr(3, Hi(rgb[1]) - static_cast<int32_t>(Clamp8(diff_hi + Hi(last[1]))));
  if (sym & 32) {
    const int32_t d = (diff_hi + Hi(rgb[1]) - Hi(last[1])) / 2;
    corr(5, Hi(rgb[2]) - static_cast<int32_t>(Clamp8(d + Hi(last[2]))));
  }
  return sym;
}

uint16_t DecodeNir(ArithmeticDecoder* dec, NirModels* m, uint16_t last) {
  const uint32_t sym = dec->DecodeSymbol(&m->byte_used);
  uint32_t lo = Lo(last), hi = Hi(last);
  if (sym & 1) lo = (dec->DecodeSymbol(&m->diff[0]) + lo) & 255;
  if (sym & 2) hi = (dec->DecodeSymbol(&m->diff[1]) + hi) & 255;
  return static_cast<uint16_t>(hi << 8 | lo);
}

void EncodeNir(ArithmeticEncoder* enc, NirModels* m, uint16_t last, uint16_t nir) {
  const uint32_t sym = (Lo(last) != Lo(nir) ? 1u : 0u) | (Hi(last) != Hi(nir) ? 2u : 0u);
  enc->EncodeSymbol(&m->byte_used, sym);
  if (sym & 1) enc->EncodeSymbol(&m->diff[0], static_cast<uint8_t>(Lo(nir) - Lo(last)));
  if (sym & 2) enc->EncodeSymbol(&m->diff[1], static_cast<uint8_t>(Hi(nir) - Hi(last)));
}

}  // namespace candi::io::laz
