// The layered chunked compressor of LASzip (compressor 3) for LAS 1.4 point formats 6-8: the
// items POINT14, RGB14, RGBNIR14 and BYTE14, version 3.
//
// A chunk holds the first record raw, the chunk's point count, the byte size of every layer of
// every item, then the layers. Each layer is an independent arithmetic stream; a zero-size layer
// means its field never changes within the chunk. Every item keeps four "contexts" (models and
// last values), one per scanner channel; POINT14 decodes the channel and the other items follow
// it. The decoding mirrors LASzip's lasreaditemcompressed_v3.cpp step for step, including its
// quirks (marked "LASzip quirk" below): the encoder's models saw that exact state, so any
// deviation desynchronises the streams. One exception: NIR follows LASzip's writer (as laz-perf
// and laz-rs do) where LASzip's v3 reader does not mirror it (see ColorDecoder::Decode).
// Item version 4 and WAVEPACKET14 are refused with a LazError naming the item. The encoders, the
// exact inverse, are in laz_layered_encode.cc.
#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "io/laz/laz_format.h"
#include "io/laz/laz_layered_items_internal.h"

namespace candi::io::laz::layered {
namespace {

// GPS time codes of the multi model (LASZIP_GPSTIME_MULTI*).
constexpr int32_t kGpsMulti = 500;
constexpr int32_t kGpsMultiMinus = -10;
constexpr uint32_t kGpsCodeFull = kGpsMulti - kGpsMultiMinus + 1;  // 511
// A valid stream switches sequence at most twice a point; more means a corrupt stream that could
// otherwise spin on near-certain symbols without consuming bytes.
constexpr int kMaxSequenceHops = 8;

}  // namespace

uint32_t Point14Decoder::Start(const uint8_t* first, const LayerSpan* layers) {
  // The XY layer is always decoded (as in LASzip); an empty one overruns at once.
  dec_[kXY].Init(layers[kXY].data, layers[kXY].data + layers[kXY].size);
  active_[kXY] = true;
  for (int l = kZ; l < kPoint14Layers; ++l) active_[l] = StartLayer(layers[l], &dec_[l]);
  const Point14 seed = UnpackPoint14(first);
  current_ = seed.scanner_channel;
  contexts_[current_] = std::make_unique<Point14Context>(seed, active_);
  return current_;
}

uint32_t Point14Decoder::Decode(uint8_t* out) {
  Point14Context* c = contexts_[current_].get();
  const Point14& prev = c->last;
  // Context of the change bits: the last point single/first/last/intermediate and its GPS change.
  const uint32_t lpr = (prev.return_number == 1 ? 1u : 0u) |
                       (prev.return_number >= prev.number_of_returns ? 2u : 0u) |
                       (prev.gps_time_change ? 4u : 0u);
  const uint32_t changed = dec_[kXY].DecodeSymbol(&c->changed_values[lpr]);
  // LASzip quirk: LASreadPoint::read resets the items' context to 0 for every point and POINT14
  // sets it only when the channel changes, so the other items see channel 0 on all other points.
  uint32_t item_context = 0;
  if (changed & (1u << 6)) {
    c = SwitchChannel(c);
    item_context = current_;
  }
  const bool gps_change = (changed & (1u << 4)) != 0;
  DecodeReturns(c, changed, gps_change);
  DecodeXYZ(c, gps_change);
  DecodeAttributes(c, changed, gps_change);
  if (active_[kGps] && gps_change) {
    DecodeGpsTime(c);
    c->last.gps_time = c->gps.time[c->gps.last];
  }
  PackPoint14(c->last, out);
  c->last.gps_time_change = gps_change;
  return item_context;
}

Point14Context* Point14Decoder::SwitchChannel(Point14Context* from) {
  const uint32_t diff = dec_[kXY].DecodeSymbol(&from->scanner_channel);
  const uint32_t channel = (current_ + diff + 1) % 4;
  // A channel's first point starts from the previous channel's last point and fresh models.
  if (!contexts_[channel]) {
    contexts_[channel] = std::make_unique<Point14Context>(from->last, active_);
  }
  current_ = channel;
  Point14Context* c = contexts_[channel].get();
  c->last.scanner_channel = static_cast<uint8_t>(channel);
  return c;
}

void Point14Decoder::DecodeReturns(Point14Context* c, uint32_t changed, bool gps_change) {
  ArithmeticDecoder& dec = dec_[kXY];
  Point14& p = c->last;
  const uint32_t last_n = p.number_of_returns, last_r = p.return_number;
  uint32_t n = last_n, r = last_r;
  if (changed & (1u << 2)) n = dec.DecodeSymbol(LazyModel(&c->number_of_returns[last_n], 16));
  switch (changed & 3) {
    case 1:
      r = (last_r + 1) % 16;
      break;
    case 2:
      r = (last_r + 15) % 16;
      break;
    case 3:  // a jump other than +-1: coded directly, or relative when the GPS time is the same
      r = gps_change ? dec.DecodeSymbol(LazyModel(&c->return_number[last_r], 16))
                     : (last_r + dec.DecodeSymbol(&c->return_number_gps_same) + 2) % 16;
      break;
    default:
      break;
  }
  p.number_of_returns = static_cast<uint8_t>(n & 15);
  p.return_number = static_cast<uint8_t>(r & 15);
}

void Point14Decoder::DecodeXYZ(Point14Context* c, bool gps_change) {
  Point14& p = c->last;
  const uint32_t n = p.number_of_returns, r = p.return_number;
  const uint32_t median = kReturnMap6[n][r] << 1 | (gps_change ? 1u : 0u);
  const uint32_t single = n == 1 ? 1u : 0u;
  int32_t diff = c->dx.Decompress(&dec_[kXY], c->x_diff_median[median].Get(), single);
  p.x = WrapAdd(p.x, diff);
  c->x_diff_median[median].Add(diff);
  diff = c->dy.Decompress(&dec_[kXY], c->y_diff_median[median].Get(),
                          single + EvenCapped(c->dx.k(), 20));
  p.y = WrapAdd(p.y, diff);
  c->y_diff_median[median].Add(diff);
  if (active_[kZ]) {
    const uint32_t level = ReturnLevel(n, r);
    const uint32_t k = (c->dx.k() + c->dy.k()) / 2;
    p.z = c->z.Decompress(&dec_[kZ], c->last_z[level], single + EvenCapped(k, 18));
    c->last_z[level] = p.z;
  }
}

void Point14Decoder::DecodeAttributes(Point14Context* c, uint32_t changed, bool gps_change) {
  Point14& p = c->last;
  const uint32_t n = p.number_of_returns, r = p.return_number;
  const uint32_t cpr = (r == 1 ? 2u : 0u) + (r >= n ? 1u : 0u);  // single 3, first 2, last 1
  if (active_[kClass]) {
    const uint32_t ctx = ((p.classification & 0x1Fu) << 1) + (cpr == 3 ? 1u : 0u);
    p.classification =
        static_cast<uint8_t>(dec_[kClass].DecodeSymbol(LazyModel(&c->classification[ctx], 256)));
  }
  if (active_[kFlags]) {
    const uint32_t last =
        p.edge_of_flight_line << 5 | p.scan_direction << 4 | p.classification_flags;
    const uint32_t flags = dec_[kFlags].DecodeSymbol(LazyModel(&c->flags[last & 63], 64));
    p.edge_of_flight_line = (flags >> 5) & 1;
    p.scan_direction = (flags >> 4) & 1;
    p.classification_flags = flags & 15;
  }
  if (active_[kIntensity]) {
    const uint32_t ctx = cpr << 1 | (gps_change ? 1u : 0u);
    p.intensity = static_cast<uint16_t>(
        c->intensity.Decompress(&dec_[kIntensity], c->last_intensity[ctx], cpr));
    c->last_intensity[ctx] = p.intensity;
  }
  if (active_[kScanAngle] && (changed & (1u << 3))) {
    p.scan_angle = static_cast<int16_t>(static_cast<uint16_t>(
        c->scan_angle.Decompress(&dec_[kScanAngle], p.scan_angle, gps_change ? 1 : 0)));
  }
  if (active_[kUserData]) {
    p.user_data = static_cast<uint8_t>(
        dec_[kUserData].DecodeSymbol(LazyModel(&c->user_data[p.user_data / 4], 256)));
  }
  if (active_[kSource] && (changed & (1u << 5))) {
    p.point_source =
        static_cast<uint16_t>(c->point_source.Decompress(&dec_[kSource], p.point_source, 0));
  }
}

// LASzip read_gps_time: the time is predicted in the active sequence; symbols switch sequence,
// start a new one (full 64-bit time) or code the difference as a multiple of the last one.
void Point14Decoder::DecodeGpsTime(Point14Context* c) {
  GpsSequences& g = c->gps;
  ArithmeticDecoder& dec = dec_[kGps];
  for (int hop = 0; hop <= kMaxSequenceHops; ++hop) {
    if (g.diff[g.last] == 0) {
      const uint32_t multi = dec.DecodeSymbol(c->gps_no_diff.get());
      if (multi == 0) {  // the difference fits in 32 bits
        g.diff[g.last] = c->gps_time.Decompress(&dec, 0, 0);
        g.time[g.last] += static_cast<uint64_t>(static_cast<int64_t>(g.diff[g.last]));
        g.extreme_count[g.last] = 0;
        return;
      }
      if (multi == 1) return NewGpsSequence(c);
      g.last = (g.last + multi - 1) & 3;
      continue;
    }
    const uint32_t multi = dec.DecodeSymbol(c->gps_multi.get());
    if (multi < kGpsCodeFull) {
      g.time[g.last] += static_cast<uint64_t>(static_cast<int64_t>(DecodeGpsDiff(c, multi)));
      return;
    }
    if (multi == kGpsCodeFull) return NewGpsSequence(c);
    g.last = (g.last + multi - kGpsCodeFull) & 3;
  }
  throw LazError("POINT14 layer GPS time is corrupt (more than " +
                 std::to_string(kMaxSequenceHops) + " time-sequence switches for one point)");
}

// The difference to the active sequence's last time, coded against `multi` times its last
// difference; repeated extreme multipliers make the new difference the reference.
int32_t Point14Decoder::DecodeGpsDiff(Point14Context* c, uint32_t multi) {
  GpsSequences& g = c->gps;
  ArithmeticDecoder& dec = dec_[kGps];
  IntegerCoder& ic = c->gps_time;
  int32_t& last_diff = g.diff[g.last];
  int32_t& extreme = g.extreme_count[g.last];
  auto count_extreme = [&](int32_t diff) {
    if (++extreme > 3) last_diff = diff, extreme = 0;
    return diff;
  };
  const int32_t m = static_cast<int32_t>(multi);
  if (m == 1) {
    extreme = 0;
    return ic.Decompress(&dec, last_diff, 1);
  }
  if (m == 0) return count_extreme(ic.Decompress(&dec, 0, 7));
  if (m < kGpsMulti) return ic.Decompress(&dec, WrapMul(m, last_diff), m < 10 ? 2 : 3);
  if (m == kGpsMulti) return count_extreme(ic.Decompress(&dec, WrapMul(m, last_diff), 4));
  const int32_t negative = kGpsMulti - m;  // -1 .. -10
  if (negative > kGpsMultiMinus) return ic.Decompress(&dec, WrapMul(negative, last_diff), 5);
  return count_extreme(ic.Decompress(&dec, WrapMul(kGpsMultiMinus, last_diff), 6));
}

// A time too far from every sequence: the upper 32 bits are predicted from the active sequence,
// the lower 32 stored raw; it starts the next sequence slot.
void Point14Decoder::NewGpsSequence(Point14Context* c) {
  GpsSequences& g = c->gps;
  ArithmeticDecoder& dec = dec_[kGps];
  g.next = (g.next + 1) & 3;
  const int32_t high = c->gps_time.Decompress(
      &dec, static_cast<int32_t>(static_cast<uint32_t>(g.time[g.last] >> 32)), 8);
  const uint32_t low = dec.ReadInt();
  g.time[g.next] = uint64_t{static_cast<uint32_t>(high)} << 32 | low;
  g.last = g.next;
  g.diff[g.last] = 0;
  g.extreme_count[g.last] = 0;
}

int Point14Decoder::OverrunLayer() const {
  for (int l = 0; l < kPoint14Layers; ++l) {
    if (active_[l] && dec_[l].overrun()) return l;
  }
  return -1;
}

// ---------------------------------------------------------------------------------------------
// RGB14 / RGBNIR14

void ColorDecoder::Start(const uint8_t* first, const LayerSpan* layers, uint32_t context) {
  rgb_active_ = StartLayer(layers[0], &rgb_dec_);
  nir_active_ = nir_ && StartLayer(layers[1], &nir_dec_);
  const uint16_t seed[4] = {LoadU16(first), LoadU16(first + 2), LoadU16(first + 4),
                            static_cast<uint16_t>(nir_ ? LoadU16(first + 6) : 0)};
  current_ = context;
  InitContext(&contexts_[context], seed);
}

void ColorDecoder::InitContext(ColorContext* c, const uint16_t* seed) const {
  c->used = true;
  std::copy(seed, seed + 4, c->last.begin());
  if (rgb_active_) c->rgb = std::make_unique<RgbModels>();
  if (nir_active_) c->nir = std::make_unique<NirModels>();
}

void ColorDecoder::Decode(uint8_t* out, uint32_t context) {
  uint16_t* last = FollowContext(&contexts_, &current_, context,
                                 [&](ColorContext* c, const ColorContext& from) {
                                   InitContext(c, from.last.data());
                                 })
                       ->last.data();
  ColorContext& c = contexts_[current_];
  uint16_t rgb[3] = {last[0], last[1], last[2]};
  if (rgb_active_) {
    DecodeRgb(&rgb_dec_, c.rgb.get(), last, rgb);
    std::copy(rgb, rgb + 3, last);
  }
  for (int i = 0; i < 3; ++i) StoreU16(out + 2 * i, rgb[i]);
  if (!nir_) return;
  // As LASzip's writer (and laz-perf, laz-rs) does, NIR goes to `last` with RGB. (LASzip's own
  // v3 reader stores it in the current context's record instead, which does not mirror its
  // writer when a context is revisited; verified against laz-perf-encoded multi-channel data.)
  uint16_t nir = last[3];
  if (nir_active_) {
    nir = DecodeNir(&nir_dec_, c.nir.get(), last[3]);
    last[3] = nir;
  }
  StoreU16(out + 6, nir);
}

int ColorDecoder::OverrunLayer() const {
  if (rgb_active_ && rgb_dec_.overrun()) return 0;
  if (nir_active_ && nir_dec_.overrun()) return 1;
  return -1;
}

// ---------------------------------------------------------------------------------------------
// BYTE14

void ByteDecoder::Start(const uint8_t* first, const LayerSpan* layers, uint32_t context) {
  for (uint32_t i = 0; i < count_; ++i) active_[i] = StartLayer(layers[i], &dec_[i]);
  current_ = context;
  InitContext(&contexts_[context], first);
}

void ByteDecoder::InitContext(ByteContext* c, const uint8_t* seed) const {
  c->used = true;
  c->last.assign(seed, seed + count_);
  c->models.clear();
  c->models.reserve(count_);
  for (uint32_t i = 0; i < count_; ++i) c->models.emplace_back(active_[i] ? 256 : 2);
}

void ByteDecoder::Decode(uint8_t* out, uint32_t context) {
  uint8_t* last = FollowContext(&contexts_, &current_, context,
                                [&](ByteContext* c, const ByteContext& from) {
                                  InitContext(c, from.last.data());
                                })
                      ->last.data();
  SymbolModel* models = contexts_[current_].models.data();
  for (uint32_t i = 0; i < count_; ++i) {
    if (active_[i]) last[i] = static_cast<uint8_t>(last[i] + dec_[i].DecodeSymbol(&models[i]));
    out[i] = last[i];
  }
}

int ByteDecoder::OverrunLayer() const {
  for (uint32_t i = 0; i < count_; ++i) {
    if (active_[i] && dec_[i].overrun()) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace candi::io::laz::layered

namespace candi::io::laz {
namespace {

using layered::ByteDecoder;
using layered::ColorDecoder;
using layered::LayerSpan;
using layered::Point14Decoder;

using layered::LoadU32;

// The layers an item stores, in stream order.
std::vector<std::string> LayerNames(const Item& item) {
  switch (item.type) {
    case kPoint14:
      return {"channel/returns/XY", "Z",         "classification", "flags",   "intensity",
              "scan angle",         "user data", "point source",   "GPS time"};
    case kRgb14:
      return {"RGB"};
    case kRgbNir14:
      return {"RGB", "NIR"};
    default: {
      std::vector<std::string> names;
      for (int i = 0; i < item.size; ++i) names.push_back("extra byte " + std::to_string(i));
      return names;
    }
  }
}

std::string ItemDescription(const Item& item) {
  return ItemTypeName(item.type) + " v" + std::to_string(item.version);
}

// The record size of a layered item type, or -1 for BYTE14 (any size > 0).
int FixedSize(uint16_t type) {
  return type == kPoint14 ? 30 : type == kRgb14 ? 6 : type == kRgbNir14 ? 8 : -1;
}

// Throws unless the items are POINT14 first, then at most one colour item and one BYTE14, all
// version 3 with their fixed sizes.
void CheckItems(const std::vector<Item>& items) {
  if (items.empty() || items[0].type != kPoint14) {
    throw LazError("layered LAZ chunk: the first item must be POINT14");
  }
  int points = 0, colors = 0, bytes = 0;
  for (const Item& item : items) {
    const bool known = item.type == kPoint14 || item.type == kRgb14 || item.type == kRgbNir14 ||
                       item.type == kByte14;
    if (!known || item.version != 3) {
      throw LazError("layered LAZ chunk: item " + ItemDescription(item) +
                     " is not supported; candi decodes POINT14, RGB14, RGBNIR14 and BYTE14 of "
                     "version 3");
    }
    const int expected = FixedSize(item.type);
    if ((expected > 0 && item.size != expected) || item.size == 0) {
      throw LazError("layered LAZ chunk: item " + ItemDescription(item) + " has size " +
                     std::to_string(item.size) + "; must be " +
                     (expected > 0 ? std::to_string(expected) : std::string("> 0")));
    }
    points += item.type == kPoint14;
    colors += item.type == kRgb14 || item.type == kRgbNir14;
    bytes += item.type == kByte14;
    if (points > 1 || colors > 1 || bytes > 1) {
      throw LazError("layered LAZ chunk: item " + ItemDescription(item) + " appears twice");
    }
  }
}

// The layers of all items located in the chunk; every span lies inside [data, data + size).
struct LayerDirectory {
  std::vector<LayerSpan> spans;     // all items' layers in stream order
  std::vector<size_t> first_layer;  // per item: index of its first span
};

// Reads the point count and the layer sizes after the raw first record (at `pos`), checking each
// layer against the bytes the chunk really has.
LayerDirectory ReadLayerDirectory(const std::vector<Item>& items, const uint8_t* data, size_t size,
                                  size_t pos, uint32_t points) {
  auto need = [&](size_t bytes, const std::string& what) {
    if (size - pos < bytes) {
      throw LazError("layered LAZ chunk: " + what + " at byte " + std::to_string(pos) +
                     " lies beyond the chunk's " + std::to_string(size) + " bytes");
    }
  };
  need(4, "the point count");
  const uint32_t stored = LoadU32(data + pos);
  pos += 4;
  if (stored != points) {
    throw LazError("layered LAZ chunk: stores " + std::to_string(stored) + " points; the chunk " +
                   "table says " + std::to_string(points));
  }
  LayerDirectory dir;
  std::vector<std::vector<std::string>> names;
  for (const Item& item : items) {
    dir.first_layer.push_back(dir.spans.size());
    names.push_back(LayerNames(item));
    for (size_t l = 0; l < names.back().size(); ++l) {
      need(4, "the layer sizes of " + ItemTypeName(item.type));
      dir.spans.push_back({nullptr, LoadU32(data + pos)});
      pos += 4;
    }
  }
  for (size_t i = 0; i < items.size(); ++i) {
    const size_t end = i + 1 < items.size() ? dir.first_layer[i + 1] : dir.spans.size();
    for (size_t l = dir.first_layer[i]; l < end; ++l) {
      LayerSpan& span = dir.spans[l];
      const size_t index = l - dir.first_layer[i];
      if (size - pos < span.size) {
        throw LazError("layered LAZ chunk: " + ItemTypeName(items[i].type) + " layer " +
                       names[i][index] + " (" + std::to_string(index + 1) + " of " +
                       std::to_string(end - dir.first_layer[i]) + ") claims " +
                       std::to_string(span.size) + " bytes at byte " + std::to_string(pos) +
                       " but the chunk has only " + std::to_string(size - pos) + " left");
      }
      span.data = data + pos;
      pos += span.size;
    }
  }
  return dir;
}

// Throws naming the first layer whose decoder read past its bytes.
void CheckOverrun(const Item& item, int layer) {
  if (layer < 0) return;
  const std::vector<std::string> names = LayerNames(item);
  throw LazError("layered LAZ chunk: " + ItemTypeName(item.type) + " layer " + names[layer] +
                 " is corrupt (its decoder ran past the layer's bytes)");
}

}  // namespace

layered::ItemSet layered::ItemSetOf(const std::vector<Item>& items) {
  CheckItems(items);
  ItemSet set;
  for (size_t i = 0; i < items.size(); ++i) {
    if (items[i].type == kRgb14 || items[i].type == kRgbNir14) {
      set.color = static_cast<int>(i), set.color_offset = set.record;
      set.nir = items[i].type == kRgbNir14;
    } else if (items[i].type == kByte14) {
      set.extra = static_cast<int>(i), set.extra_offset = set.record;
      set.extra_count = items[i].size;
    }
    set.record += items[i].size;
  }
  return set;
}

void DecodeLayeredChunk(const std::vector<Item>& items, const uint8_t* data, size_t size,
                        uint32_t points, uint8_t* out) {
  const layered::ItemSet set = layered::ItemSetOf(items);
  if (points == 0) return;
  const size_t record = set.record;
  if (size < record) {
    throw LazError("layered LAZ chunk: " + std::to_string(size) + " bytes cannot hold the raw " +
                   "first record of " + std::to_string(record) + " bytes");
  }
  std::memcpy(out, data, record);
  const LayerDirectory dir = ReadLayerDirectory(items, data, size, record, points);
  if (points == 1) return;  // only the raw record; no stream is started

  Point14Decoder point;
  std::unique_ptr<ColorDecoder> color;
  std::unique_ptr<ByteDecoder> extra;
  uint32_t context = point.Start(out, &dir.spans[dir.first_layer[0]]);
  if (set.color >= 0) {
    color = std::make_unique<ColorDecoder>(set.nir);
    color->Start(out + set.color_offset, &dir.spans[dir.first_layer[set.color]], context);
  }
  if (set.extra >= 0) {
    extra = std::make_unique<ByteDecoder>(set.extra_count);
    extra->Start(out + set.extra_offset, &dir.spans[dir.first_layer[set.extra]], context);
  }
  uint8_t* rec = out + record;
  for (uint32_t i = 1; i < points; ++i, rec += record) {
    context = point.Decode(rec);
    if (color) color->Decode(rec + set.color_offset, context);
    if (extra) extra->Decode(rec + set.extra_offset, context);
  }
  CheckOverrun(items[0], point.OverrunLayer());
  if (color) CheckOverrun(items[set.color], color->OverrunLayer());
  if (extra) CheckOverrun(items[set.extra], extra->OverrunLayer());
}

}  // namespace candi::io::laz
