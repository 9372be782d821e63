// The encoders of LASzip's layered chunked compressor (compressor 3, items of version 3) for LAS
// 1.4 point formats 6-8: the exact inverse of the decoders in laz_layered.cc, whose models they
// feed the same symbols in the same order, so that a chunk decodes to its records and matches
// LASzip's bytes.
#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <vector>

#include "io/laz/laz_format.h"
#include "io/laz/laz_layered_items_internal.h"

namespace candi::io::laz::layered {

// ---------------------------------------------------------------------------------------------
// Encoders

namespace {

void PutU32(uint32_t v, std::vector<uint8_t>* out) {
  uint8_t b[4];
  StoreU32(b, v);
  out->insert(out->end(), b, b + 4);
}

// Ends a layer; stores its size (0 when unchanged: the decoder keeps the field) and bytes.
void FinishLayer(ArithmeticEncoder* enc, bool stored, std::vector<uint8_t>* sizes,
                 std::vector<uint8_t>* bytes) {
  enc->Done();
  PutU32(stored ? static_cast<uint32_t>(enc->size()) : 0, sizes);
  if (stored) bytes->insert(bytes->end(), enc->data(), enc->data() + enc->size());
}

uint32_t Flags(const Point14& p) {
  return uint32_t{p.edge_of_flight_line} << 5 | uint32_t{p.scan_direction} << 4 |
         p.classification_flags;
}

}  // namespace

uint32_t Point14Encoder::Start(const uint8_t* first,
                               const std::array<bool, kPoint14Layers>& coded) {
  for (ArithmeticEncoder& e : enc_) e.Init();
  changed_.fill(false);
  coded_ = coded;
  const Point14 seed = UnpackPoint14(first);
  current_ = seed.scanner_channel;
  std::array<bool, kPoint14Layers> all;
  all.fill(true);
  contexts_[current_] = std::make_unique<Point14Context>(seed, all);
  return current_;
}

uint32_t Point14Encoder::Encode(const uint8_t* record) {
  const Point14 p = UnpackPoint14(record);
  Point14Context* c = contexts_[current_].get();
  const uint32_t lpr = (c->last.return_number == 1 ? 1u : 0u) |
                       (c->last.return_number >= c->last.number_of_returns ? 2u : 0u) |
                       (c->last.gps_time_change ? 4u : 0u);
  const uint32_t channel = p.scanner_channel;
  // Changes are relative to the last point of the channel (of the current one for a new channel,
  // which starts from it).
  const Point14& last =
      channel != current_ && contexts_[channel] ? contexts_[channel]->last : c->last;
  const bool source_change = p.point_source != last.point_source;
  // The time's bits, where LASzip compares the doubles: the same for all times but -0.0/+0.0
  // and NaN, which this way survive bit for bit.
  const bool gps_change = p.gps_time != last.gps_time;
  const bool angle_change = p.scan_angle != last.scan_angle;
  const uint32_t n = p.number_of_returns, r = p.return_number;
  const uint32_t last_r = last.return_number;
  uint32_t changed = (channel != current_ ? 64u : 0u) | (source_change ? 32u : 0u) |
                     (gps_change ? 16u : 0u) | (angle_change ? 8u : 0u) |
                     (n != last.number_of_returns ? 4u : 0u);
  if (r != last_r) changed |= r == (last_r + 1) % 16 ? 1u : r == (last_r + 15) % 16 ? 2u : 3u;
  enc_[kXY].EncodeSymbol(&c->changed_values[lpr], changed);
  uint32_t item_context = 0;
  if (changed & 64) {
    enc_[kXY].EncodeSymbol(&c->scanner_channel, (channel + 3 - current_) % 4);
    if (!contexts_[channel]) {
      std::array<bool, kPoint14Layers> all;
      all.fill(true);
      contexts_[channel] = std::make_unique<Point14Context>(c->last, all);
    }
    current_ = item_context = channel;
    c = contexts_[channel].get();
  }
  EncodeReturns(c, p, changed, gps_change);
  EncodeXYZ(c, p, gps_change);
  EncodeAttributes(c, p, angle_change, source_change, gps_change);
  c->last = p;
  c->last.gps_time_change = gps_change;
  return item_context;
}

void Point14Encoder::EncodeReturns(Point14Context* c, const Point14& p, uint32_t changed,
                                   bool gps_change) {
  ArithmeticEncoder& enc = enc_[kXY];
  const uint32_t last_n = c->last.number_of_returns, last_r = c->last.return_number;
  if (changed & (1u << 2)) {
    enc.EncodeSymbol(LazyModel(&c->number_of_returns[last_n], 16), p.number_of_returns);
  }
  if ((changed & 3) != 3) return;
  if (gps_change) {
    enc.EncodeSymbol(LazyModel(&c->return_number[last_r], 16), p.return_number);
  } else {  // r = (last_r + sym + 2) % 16
    enc.EncodeSymbol(&c->return_number_gps_same, (p.return_number + 14 - last_r) % 16);
  }
}

void Point14Encoder::EncodeXYZ(Point14Context* c, const Point14& p, bool gps_change) {
  const uint32_t n = p.number_of_returns, r = p.return_number;
  const uint32_t median = kReturnMap6[n][r] << 1 | (gps_change ? 1u : 0u);
  const uint32_t single = n == 1 ? 1u : 0u;
  int32_t diff = WrapSub(p.x, c->last.x);
  c->dx.Compress(&enc_[kXY], c->x_diff_median[median].Get(), diff, single);
  c->x_diff_median[median].Add(diff);
  diff = WrapSub(p.y, c->last.y);
  c->dy.Compress(&enc_[kXY], c->y_diff_median[median].Get(), diff,
                 single + EvenCapped(c->dx.k(), 20));
  c->y_diff_median[median].Add(diff);
  const uint32_t level = ReturnLevel(n, r);
  const uint32_t k = (c->dx.k() + c->dy.k()) / 2;
  c->z.Compress(&enc_[kZ], c->last_z[level], p.z, single + EvenCapped(k, 18));
  c->last_z[level] = p.z;
}

void Point14Encoder::EncodeAttributes(Point14Context* c, const Point14& p, bool angle_change,
                                      bool source_change, bool gps_change) {
  const Point14& last = c->last;
  const uint32_t n = p.number_of_returns, r = p.return_number;
  const uint32_t cpr = (r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u);  // single 3, first 2, last 1
  if (coded_[kClass]) {
    changed_[kClass] = changed_[kClass] || p.classification != last.classification;
    const uint32_t class_ctx = ((last.classification & 0x1Fu) << 1) + (cpr == 3 ? 1u : 0u);
    enc_[kClass].EncodeSymbol(LazyModel(&c->classification[class_ctx], 256), p.classification);
  }
  if (coded_[kFlags]) {
    changed_[kFlags] = changed_[kFlags] || Flags(p) != Flags(last);
    enc_[kFlags].EncodeSymbol(LazyModel(&c->flags[Flags(last)], 64), Flags(p));
  }
  if (coded_[kIntensity]) {
    changed_[kIntensity] = changed_[kIntensity] || p.intensity != last.intensity;
    const uint32_t intensity_ctx = cpr << 1 | (gps_change ? 1u : 0u);
    c->intensity.Compress(&enc_[kIntensity], c->last_intensity[intensity_ctx], p.intensity, cpr);
    c->last_intensity[intensity_ctx] = p.intensity;
  }
  if (angle_change) {
    changed_[kScanAngle] = true;
    c->scan_angle.Compress(&enc_[kScanAngle], last.scan_angle, p.scan_angle, gps_change ? 1 : 0);
  }
  if (coded_[kUserData]) {
    changed_[kUserData] = changed_[kUserData] || p.user_data != last.user_data;
    enc_[kUserData].EncodeSymbol(LazyModel(&c->user_data[last.user_data / 4], 256), p.user_data);
  }
  if (source_change) {
    changed_[kSource] = true;
    c->point_source.Compress(&enc_[kSource], last.point_source, p.point_source, 0);
  }
  if (gps_change) {
    changed_[kGps] = true;
    EncodeGpsTime(&enc_[kGps], {c->gps_no_diff.get(), c->gps_multi.get(), &c->gps_time, false},
                  p.gps_time, &c->gps);
  }
}

void Point14Encoder::Finish(std::vector<uint8_t>* sizes, std::vector<uint8_t>* bytes) {
  for (int l = 0; l < kPoint14Layers; ++l) {
    FinishLayer(&enc_[l], l == kXY || l == kZ || changed_[l], sizes, bytes);
  }
}

ColorEncoder::ColorEncoder(bool nir, const uint8_t* first, uint32_t context, bool code_rgb,
                           bool code_nir)
    : nir_(nir), code_rgb_(code_rgb), code_nir_(code_nir), current_(context) {
  ColorContext& c = contexts_[context];
  c.used = true;
  for (int i = 0; i < (nir_ ? 4 : 3); ++i) c.last[i] = LoadU16(first + 2 * i);
  c.rgb = std::make_unique<RgbModels>();
  c.nir = std::make_unique<NirModels>();
}

void ColorEncoder::Encode(const uint8_t* item, uint32_t context) {
  uint16_t* last = FollowContext(&contexts_, &current_, context,
                                 [](ColorContext* c, const ColorContext& from) {
                                   c->used = true;
                                   c->last = from.last;
                                   c->rgb = std::make_unique<RgbModels>();
                                   c->nir = std::make_unique<NirModels>();
                                 })
                       ->last.data();
  ColorContext& c = contexts_[current_];
  const uint16_t rgb[3] = {LoadU16(item), LoadU16(item + 2), LoadU16(item + 4)};
  if (code_rgb_) rgb_changed_ = EncodeRgb(&rgb_enc_, c.rgb.get(), last, rgb) != 0 || rgb_changed_;
  std::copy(rgb, rgb + 3, last);
  if (!nir_) return;
  const uint16_t nir = LoadU16(item + 6);
  if (code_nir_) {
    EncodeNir(&nir_enc_, c.nir.get(), last[3], nir);
    nir_changed_ = nir_changed_ || nir != last[3];
  }
  last[3] = nir;
}

void ColorEncoder::Finish(std::vector<uint8_t>* sizes, std::vector<uint8_t>* bytes) {
  FinishLayer(&rgb_enc_, rgb_changed_, sizes, bytes);
  if (nir_) FinishLayer(&nir_enc_, nir_changed_, sizes, bytes);
}

ByteEncoder::ByteEncoder(uint32_t count, const uint8_t* first, uint32_t context)
    : enc_(count), changed_(count), current_(context) {
  ByteContext& c = contexts_[context];
  c.used = true;
  c.last.assign(first, first + count);
  c.models.assign(count, SymbolModel(256));
}

void ByteEncoder::Encode(const uint8_t* item, uint32_t context) {
  uint8_t* last = FollowContext(&contexts_, &current_, context,
                                [&](ByteContext* c, const ByteContext& from) {
                                  c->used = true;
                                  c->last = from.last;
                                  c->models.assign(enc_.size(), SymbolModel(256));
                                })
                      ->last.data();
  SymbolModel* models = contexts_[current_].models.data();
  for (size_t i = 0; i < enc_.size(); ++i) {
    enc_[i].EncodeSymbol(&models[i], static_cast<uint8_t>(item[i] - last[i]));
    if (item[i] != last[i]) changed_[i] = 1, last[i] = item[i];
  }
}

void ByteEncoder::Finish(std::vector<uint8_t>* sizes, std::vector<uint8_t>* bytes) {
  for (size_t i = 0; i < enc_.size(); ++i) FinishLayer(&enc_[i], changed_[i] != 0, sizes, bytes);
}

}  // namespace candi::io::laz::layered

namespace candi::io::laz {

namespace {

// The layers a chunk codes. A layer is stored only when its field changed in the chunk, so the
// layers of fields that are the same in every record are not coded at all: POINT14's
// classification, flags, intensity and user data, the colour's RGB and NIR.
struct CodedLayers {
  std::array<bool, layered::kPoint14Layers> point;
  bool rgb = false, nir = false;
};

CodedLayers LayersToCode(const layered::ItemSet& set, const uint8_t* records, uint32_t points) {
  using layered::kClass, layered::kFlags, layered::kIntensity, layered::kUserData;
  CodedLayers coded;
  coded.point.fill(true);
  for (layered::Point14Layer l : {kClass, kFlags, kIntensity, kUserData}) coded.point[l] = false;
  std::array<bool, layered::kPoint14Layers>& c = coded.point;
  const uint8_t* first = records;
  for (uint32_t i = 1; i < points; ++i) {
    const uint8_t* rec = records + size_t{i} * set.record;
    c[kIntensity] = c[kIntensity] || layered::LoadU16(rec + 12) != layered::LoadU16(first + 12);
    c[kFlags] = c[kFlags] || ((rec[15] ^ first[15]) & 0xCF) != 0;  // all but the channel
    c[kClass] = c[kClass] || rec[16] != first[16];
    c[kUserData] = c[kUserData] || rec[17] != first[17];
    if (set.color >= 0) {
      const uint8_t *a = rec + set.color_offset, *b = first + set.color_offset;
      coded.rgb = coded.rgb || std::memcmp(a, b, 6) != 0;
      coded.nir = coded.nir || (set.nir && std::memcmp(a + 6, b + 6, 2) != 0);
    }
  }
  return coded;
}

}  // namespace

void EncodeLayeredChunk(const std::vector<Item>& items, const uint8_t* records, uint32_t points,
                        std::vector<uint8_t>* out) {
  const layered::ItemSet set = layered::ItemSetOf(items);
  if (points == 0) return;
  out->insert(out->end(), records, records + set.record);
  std::vector<uint8_t> sizes, bytes;
  layered::PutU32(points, &sizes);
  const CodedLayers coded = LayersToCode(set, records, points);
  // As LASzip, the layers are started and ended even for a chunk of one point.
  layered::Point14Encoder point;
  std::unique_ptr<layered::ColorEncoder> color;
  std::unique_ptr<layered::ByteEncoder> extra;
  uint32_t context = point.Start(records, coded.point);
  if (set.color >= 0) {
    color = std::make_unique<layered::ColorEncoder>(set.nir, records + set.color_offset, context,
                                                    coded.rgb, coded.nir);
  }
  if (set.extra >= 0) {
    extra = std::make_unique<layered::ByteEncoder>(set.extra_count, records + set.extra_offset,
                                                   context);
  }
  const uint8_t* rec = records + set.record;
  for (uint32_t i = 1; i < points; ++i, rec += set.record) {
    context = point.Encode(rec);
    if (color) color->Encode(rec + set.color_offset, context);
    if (extra) extra->Encode(rec + set.extra_offset, context);
  }
  point.Finish(&sizes, &bytes);
  if (color) color->Finish(&sizes, &bytes);
  if (extra) extra->Finish(&sizes, &bytes);
  out->insert(out->end(), sizes.begin(), sizes.end());
  out->insert(out->end(), bytes.begin(), bytes.end());
}

}  // namespace candi::io::laz
