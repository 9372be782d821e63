// LASzip's pointwise chunked compressor (compressor 2), both directions, items of version 2:
// POINT10, GPSTIME11, RGB12 and BYTE (LASzip's LAS{read,write}ItemCompressed_*_v2; each item's
// decoder and encoder share one context struct of models and predictions). A chunk is its first
// record raw, then one arithmetic stream that codes every later record item by item, each
// predicted from the previous record (and, for POINT10, from contexts selected by the return
// number and the number of returns).
#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "core/binary_file.h"
#include "io/laz/laz_color_internal.h"
#include "io/laz/laz_format.h"
#include "io/laz/laz_gps_time_internal.h"

namespace candi::io::laz {

namespace {

// Context of a (number of returns n, return number r) pair; LASzip "completes" the table so that
// files numbering returns from 0 or swapping r and n still get distinct contexts.
constexpr uint8_t kNumberReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8},  {14, 0, 1, 3, 6, 10, 10, 9},
    {13, 1, 2, 4, 7, 11, 11, 10},    {12, 3, 4, 5, 8, 12, 12, 11},
    {11, 6, 7, 8, 9, 13, 13, 12},    {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
// |n - r|: the z prediction is the last z of the same level.
constexpr uint8_t kNumberReturnLevel[8][8] = {
    {0, 1, 2, 3, 4, 5, 6, 7}, {1, 0, 1, 2, 3, 4, 5, 6}, {2, 1, 0, 1, 2, 3, 4, 5},
    {3, 2, 1, 0, 1, 2, 3, 4}, {4, 3, 2, 1, 0, 1, 2, 3}, {5, 4, 3, 2, 1, 0, 1, 2},
    {6, 5, 4, 3, 2, 1, 0, 1}, {7, 6, 5, 4, 3, 2, 1, 0}};

// A 256-symbol model per previous byte value, created on first use (most never are, and a
// chunk would otherwise spend more time initialising 768 models than decoding).
class LazyModels {
 public:
  SymbolModel* At(uint8_t context) {
    std::unique_ptr<SymbolModel>& m = models_[context];
    if (!m) m = std::make_unique<SymbolModel>(256);
    return m.get();
  }

 private:
  std::array<std::unique_ptr<SymbolModel>, 256> models_;
};

// ---- POINT10 v2: x, y, z, intensity, return bits, class, scan angle, user data, source id ----

// What the POINT10 encoder and decoder both keep: the models and the predictions' state.
struct Point10Context {
  Point10Context() {
    for (IntegerCoder* ic : {&ic_intensity, &ic_source_id, &ic_dx, &ic_dy, &ic_z}) ic->Init();
  }
  std::array<uint16_t, 16> last_intensity{};  // LASzip predicts the 2nd point's from 0
  std::array<int32_t, 8> last_height{};
  std::array<Median5, 16> x_median, y_median;
  SymbolModel changed_values{64};
  SymbolModel scan_angle_rank[2] = {SymbolModel(256), SymbolModel(256)};
  LazyModels bit_byte, classification, user_data;
  IntegerCoder ic_intensity{16, 4}, ic_source_id{16}, ic_dx{32, 2}, ic_dy{32, 22}, ic_z{32, 20};
};

// The y coder's context from the x corrector's class, the z coder's from both.
uint32_t DyContext(uint32_t single, uint32_t k_dx) {
  return single + (k_dx < 20 ? k_dx & ~1u : 20);
}
uint32_t ZContext(uint32_t single, uint32_t k_dx, uint32_t k_dy) {
  const uint32_t k = (k_dx + k_dy) / 2;
  return single + (k < 18 ? k & ~1u : 18);
}

class Point10Decoder {
 public:
  explicit Point10Decoder(const uint8_t* first) {
    x_ = LoadLE<int32_t>(first);
    y_ = LoadLE<int32_t>(first + 4);
    z_ = LoadLE<int32_t>(first + 8);
    intensity_ = 0;
    bits_ = first[14];
    class_ = first[15];
    scan_angle_ = first[16];
    user_data_ = first[17];
    source_id_ = LoadLE<uint16_t>(first + 18);
  }

  void Code(ArithmeticDecoder* dec, uint8_t* out) {
    const uint32_t changed = dec->DecodeSymbol(&c_.changed_values);
    if (changed != 0) DecodeAttributes(dec, changed);
    const uint32_t n = (bits_ >> 3) & 7;
    const uint32_t m = kNumberReturnMap[n][bits_ & 7];
    const uint32_t l = kNumberReturnLevel[n][bits_ & 7];
    const uint32_t single = n == 1;
    const int32_t dx = c_.ic_dx.Decompress(dec, c_.x_median[m].Get(), single);
    x_ = WrapAdd(x_, dx);
    c_.x_median[m].Add(dx);
    const int32_t dy =
        c_.ic_dy.Decompress(dec, c_.y_median[m].Get(), DyContext(single, c_.ic_dx.k()));
    y_ = WrapAdd(y_, dy);
    c_.y_median[m].Add(dy);
    z_ = c_.ic_z.Decompress(dec, c_.last_height[l],
                            ZContext(single, c_.ic_dx.k(), c_.ic_dy.k()));
    c_.last_height[l] = z_;
    StoreLE<int32_t>(out, x_);
    StoreLE<int32_t>(out + 4, y_);
    StoreLE<int32_t>(out + 8, z_);
    StoreLE<uint16_t>(out + 12, intensity_);
    out[14] = bits_;
    out[15] = class_;
    out[16] = scan_angle_;
    out[17] = user_data_;
    StoreLE<uint16_t>(out + 18, source_id_);
  }

 private:
  // `changed`: bit 5 return bits, 4 intensity, 3 class, 2 scan angle, 1 user data, 0 source id.
  void DecodeAttributes(ArithmeticDecoder* dec, uint32_t changed) {
    if (changed & 32) bits_ = static_cast<uint8_t>(dec->DecodeSymbol(c_.bit_byte.At(bits_)));
    const uint32_t m = kNumberReturnMap[(bits_ >> 3) & 7][bits_ & 7];
    if (changed & 16) {
      intensity_ = static_cast<uint16_t>(
          c_.ic_intensity.Decompress(dec, c_.last_intensity[m], m < 3 ? m : 3));
      c_.last_intensity[m] = intensity_;
    } else {
      intensity_ = c_.last_intensity[m];
    }
    if (changed & 8) {
      class_ = static_cast<uint8_t>(dec->DecodeSymbol(c_.classification.At(class_)));
    }
    if (changed & 4) {
      const uint32_t delta = dec->DecodeSymbol(&c_.scan_angle_rank[(bits_ >> 6) & 1]);
      scan_angle_ = static_cast<uint8_t>(delta + scan_angle_);
    }
    if (changed & 2) {
      user_data_ = static_cast<uint8_t>(dec->DecodeSymbol(c_.user_data.At(user_data_)));
    }
    if (changed & 1) {
      source_id_ = static_cast<uint16_t>(c_.ic_source_id.Decompress(dec, source_id_));
    }
  }

  Point10Context c_;
  int32_t x_, y_, z_;
  uint16_t intensity_, source_id_;
  uint8_t bits_, class_, scan_angle_, user_data_;
};

// The inverse of Point10Decoder (LASzip LASwriteItemCompressed_POINT10_v2).
class Point10Encoder {
 public:
  explicit Point10Encoder(const uint8_t* first) { std::memcpy(last_, first, 20); }

  void Code(ArithmeticEncoder* enc, const uint8_t* item) {
    const uint32_t n = (item[14] >> 3) & 7;
    const uint32_t m = kNumberReturnMap[n][item[14] & 7];
    const uint32_t l = kNumberReturnLevel[n][item[14] & 7];
    const uint16_t intensity = LoadLE<uint16_t>(item + 12);
    const uint16_t source_id = LoadLE<uint16_t>(item + 18);
    const uint16_t last_source_id = LoadLE<uint16_t>(last_ + 18);
    const uint32_t changed = (last_[14] != item[14] ? 32u : 0u) |
                             (c_.last_intensity[m] != intensity ? 16u : 0u) |
                             (last_[15] != item[15] ? 8u : 0u) | (last_[16] != item[16] ? 4u : 0u) |
                             (last_[17] != item[17] ? 2u : 0u) |
                             (last_source_id != source_id ? 1u : 0u);
    enc->EncodeSymbol(&c_.changed_values, changed);
    if (changed & 32) enc->EncodeSymbol(c_.bit_byte.At(last_[14]), item[14]);
    if (changed & 16) {
      c_.ic_intensity.Compress(enc, c_.last_intensity[m], intensity, m < 3 ? m : 3);
      c_.last_intensity[m] = intensity;
    }
    if (changed & 8) enc->EncodeSymbol(c_.classification.At(last_[15]), item[15]);
    if (changed & 4) {
      enc->EncodeSymbol(&c_.scan_angle_rank[(item[14] >> 6) & 1],
                        static_cast<uint8_t>(item[16] - last_[16]));
    }
    if (changed & 2) enc->EncodeSymbol(c_.user_data.At(last_[17]), item[17]);
    if (changed & 1) c_.ic_source_id.Compress(enc, last_source_id, source_id);
    const uint32_t single = n == 1;
    const int32_t dx = WrapSub(LoadLE<int32_t>(item), LoadLE<int32_t>(last_));
    c_.ic_dx.Compress(enc, c_.x_median[m].Get(), dx, single);
    c_.x_median[m].Add(dx);
    const int32_t dy = WrapSub(LoadLE<int32_t>(item + 4), LoadLE<int32_t>(last_ + 4));
    c_.ic_dy.Compress(enc, c_.y_median[m].Get(), dy, DyContext(single, c_.ic_dx.k()));
    c_.y_median[m].Add(dy);
    const int32_t z = LoadLE<int32_t>(item + 8);
    c_.ic_z.Compress(enc, c_.last_height[l], z, ZContext(single, c_.ic_dx.k(), c_.ic_dy.k()));
    c_.last_height[l] = z;
    std::memcpy(last_, item, 20);
  }

 private:
  Point10Context c_;
  uint8_t last_[20];
};

// ---- GPSTIME11 v2: up to four interleaved time sequences, each with its last difference ----

constexpr uint32_t kGpsMulti = 500;
constexpr int32_t kGpsMultiMinus = -10;
constexpr uint32_t kGpsMultiUnchanged = kGpsMulti - kGpsMultiMinus + 1;  // 511
constexpr uint32_t kGpsMultiCodeFull = kGpsMulti - kGpsMultiMinus + 2;   // 512
constexpr uint32_t kGpsMultiTotal = kGpsMulti - kGpsMultiMinus + 6;      // 516

// The GPSTIME11 models and sequences, for both directions.
struct GpsTime11Context {
  explicit GpsTime11Context(const uint8_t* first) {
    g.time[0] = LoadLE<uint64_t>(first);
    ic_gps_time.Init();
  }
  GpsSequences g;
  SymbolModel multi{kGpsMultiTotal}, zero_diff{6};
  IntegerCoder ic_gps_time{32, 9};
};

class GpsTime11Decoder {
 public:
  explicit GpsTime11Decoder(const uint8_t* first) : c_(first) {}

  void Code(ArithmeticDecoder* dec, uint8_t* out) {
    // A switch to another sequence decodes that sequence's value next; an encoder switches only
    // to a sequence it can code, so a second switch in a row means corrupt data.
    for (int switches = 0; !DecodeStep(dec); ++switches) {
      if (switches == 3) throw LazError("GPSTIME11: corrupt data (repeated sequence switches)");
    }
    StoreLE<uint64_t>(out, c_.g.time[c_.g.last]);
  }

 private:
  // Returns false when the symbol switched sequences (the value follows).
  bool DecodeStep(ArithmeticDecoder* dec) {
    GpsSequences& g = c_.g;
    if (g.diff[g.last] == 0) {
      const uint32_t multi = dec->DecodeSymbol(&c_.zero_diff);
      if (multi == 1) {
        g.diff[g.last] = c_.ic_gps_time.Decompress(dec, 0, 0);
        Advance(g.diff[g.last]);
        g.extreme_count[g.last] = 0;
      } else if (multi == 2) {
        StartSequence(dec);
      } else if (multi > 2) {
        g.last = (g.last + multi - 2) & 3;
        return false;
      }
      return true;
    }
    const uint32_t multi = dec->DecodeSymbol(&c_.multi);
    if (multi == 1) {
      Advance(c_.ic_gps_time.Decompress(dec, g.diff[g.last], 1));
      g.extreme_count[g.last] = 0;
    } else if (multi < kGpsMultiUnchanged) {
      Advance(DecodeMultipleDiff(dec, multi));
    } else if (multi == kGpsMultiCodeFull) {
      StartSequence(dec);
    } else if (multi > kGpsMultiCodeFull) {
      g.last = (g.last + multi - kGpsMultiCodeFull) & 3;
      return false;
    }
    return true;
  }

  // A difference predicted as a multiple of the last one (multi != 1, < kGpsMultiUnchanged).
  int32_t DecodeMultipleDiff(ArithmeticDecoder* dec, uint32_t multi) {
    GpsSequences& g = c_.g;
    IntegerCoder& ic = c_.ic_gps_time;
    const int32_t last = g.diff[g.last];
    int32_t diff;
    bool extreme = false;
    if (multi == 0) {
      diff = ic.Decompress(dec, 0, 7);
      extreme = true;
    } else if (multi < kGpsMulti) {
      diff = ic.Decompress(dec, WrapMul(static_cast<int32_t>(multi), last), multi < 10 ? 2 : 3);
    } else if (multi == kGpsMulti) {
      diff = ic.Decompress(dec, WrapMul(kGpsMulti, last), 4);
      extreme = true;
    } else {
      const int32_t negative = static_cast<int32_t>(kGpsMulti) - static_cast<int32_t>(multi);
      if (negative > kGpsMultiMinus) {
        diff = ic.Decompress(dec, WrapMul(negative, last), 5);
      } else {
        diff = ic.Decompress(dec, WrapMul(kGpsMultiMinus, last), 6);
        extreme = true;
      }
    }
    // Repeated extreme multipliers: the sequence's step changed; adopt the new difference.
    if (extreme && ++g.extreme_count[g.last] > 3) {
      g.diff[g.last] = diff;
      g.extreme_count[g.last] = 0;
    }
    return diff;
  }

  void Advance(int32_t diff) {
    c_.g.time[c_.g.last] += static_cast<uint64_t>(static_cast<int64_t>(diff));
  }

  // A new sequence: the high 32 bits predicted from the current sequence's, the low ones raw.
  void StartSequence(ArithmeticDecoder* dec) {
    GpsSequences& g = c_.g;
    g.next = (g.next + 1) & 3;
    const int32_t high =
        c_.ic_gps_time.Decompress(dec, static_cast<int32_t>(g.time[g.last] >> 32), 8);
    g.time[g.next] = static_cast<uint64_t>(static_cast<uint32_t>(high)) << 32 | dec->ReadInt();
    g.last = g.next;
    g.diff[g.last] = 0;
    g.extreme_count[g.last] = 0;
  }

  GpsTime11Context c_;
};

class GpsTime11Encoder {
 public:
  explicit GpsTime11Encoder(const uint8_t* first) : c_(first) {}
  void Code(ArithmeticEncoder* enc, const uint8_t* item) {
    EncodeGpsTime(enc, {&c_.zero_diff, &c_.multi, &c_.ic_gps_time, true}, LoadLE<uint64_t>(item),
                  &c_.g);
  }

 private:
  GpsTime11Context c_;
};

// ---- RGB12 v2 (laz_color_internal.h): red against the last colour, green and blue against red

class Rgb12Coder {
 public:
  explicit Rgb12Coder(const uint8_t* first) {
    for (int c = 0; c < 3; ++c) last_[c] = LoadLE<uint16_t>(first + 2 * c);
  }
  void Code(ArithmeticDecoder* dec, uint8_t* out) {
    uint16_t rgb[3];
    DecodeRgb(dec, &models_, last_, rgb);
    for (int c = 0; c < 3; ++c) StoreLE<uint16_t>(out + 2 * c, last_[c] = rgb[c]);
  }
  void Code(ArithmeticEncoder* enc, const uint8_t* item) {
    uint16_t rgb[3];
    for (int c = 0; c < 3; ++c) rgb[c] = LoadLE<uint16_t>(item + 2 * c);
    EncodeRgb(enc, &models_, last_, rgb);
    std::copy(rgb, rgb + 3, last_);
  }

 private:
  uint16_t last_[3];
  RgbModels models_;
};

// ---- BYTE v2: each extra byte coded against the same byte of the last record ----

class ByteCoder {
 public:
  ByteCoder(const uint8_t* first, size_t count)
      : last_(first, first + count), models_(count, SymbolModel(256)) {}

  void Code(ArithmeticDecoder* dec, uint8_t* out) {
    for (size_t i = 0; i < last_.size(); ++i) {
      last_[i] = static_cast<uint8_t>(last_[i] + dec->DecodeSymbol(&models_[i]));
      out[i] = last_[i];
    }
  }
  void Code(ArithmeticEncoder* enc, const uint8_t* item) {
    for (size_t i = 0; i < last_.size(); ++i) {
      enc->EncodeSymbol(&models_[i], static_cast<uint8_t>(item[i] - last_[i]));
      last_[i] = item[i];
    }
  }

 private:
  std::vector<uint8_t> last_;
  std::vector<SymbolModel> models_;
};

// ---- The chunk ----

struct Layout {
  size_t length = 0;  // record bytes
  int gps = -1, rgb = -1, bytes = -1;  // item offsets in the record (-1: absent)
  size_t byte_count = 0;
};

// POINT10 first, then GPSTIME11, RGB12 and BYTE when present, in that order (what LASzip writes
// and CheckSupported accepts); the decoding order is the item order.
Layout LayoutOf(const std::vector<Item>& items) {
  Layout l;
  size_t i = 0;
  auto take = [&](uint16_t type, int* offset) {
    if (i >= items.size() || items[i].type != type) return;
    if (items[i].version != 2) {
      throw LazError("item " + ItemTypeName(type) + " version " +
                     std::to_string(items[i].version) +
                     " is not supported by the pointwise decoder; candi decodes version 2");
    }
    *offset = static_cast<int>(l.length);
    l.length += items[i].size;
    ++i;
  };
  int point = -1;
  take(kPoint10, &point);
  take(kGpsTime11, &l.gps);
  take(kRgb12, &l.rgb);
  take(kByte, &l.bytes);
  if (point != 0 || i != items.size() || (l.gps >= 0 && items[1].size != 8) ||
      items[0].size != 20 || (l.rgb >= 0 && items[l.gps >= 0 ? 2 : 1].size != 6)) {
    std::string listed;
    for (const Item& item : items) listed += (listed.empty() ? "" : ", ") + ItemTypeName(item.type);
    throw LazError("the pointwise decoder needs items POINT10, [GPSTIME11], [RGB12], [BYTE] "
                   "of their standard sizes, in this order; the chunk has " + listed);
  }
  if (l.bytes >= 0) l.byte_count = l.length - static_cast<size_t>(l.bytes);
  return l;
}

[[noreturn]] void ThrowEndsEarly(size_t size, uint32_t point) {
  throw LazError("chunk data ends early: decoding point " + std::to_string(point) +
                 " needed bytes past the chunk's " + std::to_string(size) + " bytes");
}

// A chunk's item coders (decoders or encoders), made from its first record.
template <class Point, class Gps, bool kGps, bool kRgb, bool kBytes>
struct ChunkItems {
  ChunkItems(const Layout& layout, const uint8_t* first) : l(layout), point(first) {
    if (kGps) gps = std::make_unique<Gps>(first + l.gps);
    if (kRgb) rgb = std::make_unique<Rgb12Coder>(first + l.rgb);
    if (kBytes) bytes = std::make_unique<ByteCoder>(first + l.bytes, l.byte_count);
  }
  // Decodes into (ArithmeticDecoder, uint8_t*) or encodes from (ArithmeticEncoder, const
  // uint8_t*) the next record, item by item.
  template <class Coder, class Byte>
  void Code(Coder* coder, Byte* record) {
    point.Code(coder, record);
    if constexpr (kGps) gps->Code(coder, record + l.gps);
    if constexpr (kRgb) rgb->Code(coder, record + l.rgb);
    if constexpr (kBytes) bytes->Code(coder, record + l.bytes);
  }
  const Layout& l;
  Point point;
  std::unique_ptr<Gps> gps;
  std::unique_ptr<Rgb12Coder> rgb;
  std::unique_ptr<ByteCoder> bytes;
};

// Decoders created once per chunk; the item set is a template parameter, so the per-point loop
// has no branches on the item types.
template <bool kGps, bool kRgb, bool kBytes>
void DecodeChunk(const Layout& l, const uint8_t* data, size_t size, uint32_t points,
                 uint8_t* out) {
  std::memcpy(out, data, l.length);
  if (points == 1) return;
  ChunkItems<Point10Decoder, GpsTime11Decoder, kGps, kRgb, kBytes> items(l, out);
  ArithmeticDecoder dec;
  dec.Init(data + l.length, data + size);
  uint8_t* record = out;
  for (uint32_t i = 1; i < points; ++i) {
    record += l.length;
    items.Code(&dec, record);
    if ((i & 4095) == 0 && dec.overrun()) ThrowEndsEarly(size, i);  // stop early on truncation
  }
  if (dec.overrun()) ThrowEndsEarly(size, points - 1);
}

// The inverse of DecodeChunk (LASzip LASwritePoint with the pointwise items): the first record
// raw, then one stream coding the others; a chunk of one point still ends its (empty) stream.
template <bool kGps, bool kRgb, bool kBytes>
void EncodeChunk(const Layout& l, const uint8_t* records, uint32_t points,
                 std::vector<uint8_t>* out) {
  out->insert(out->end(), records, records + l.length);
  ChunkItems<Point10Encoder, GpsTime11Encoder, kGps, kRgb, kBytes> items(l, records);
  ArithmeticEncoder enc;
  for (uint32_t i = 1; i < points; ++i) items.Code(&enc, records + i * l.length);
  enc.Done();
  out->insert(out->end(), enc.data(), enc.data() + enc.size());
}

// Calls f(gps, rgb, bytes) with std::bool_constant tags of the items present: the chunk coders
// are instantiated per item set.
template <class F>
void WithItems(const Layout& l, F&& f) {
  using Y = std::true_type;
  using N = std::false_type;
  switch ((l.gps >= 0 ? 4 : 0) | (l.rgb >= 0 ? 2 : 0) | (l.bytes >= 0 ? 1 : 0)) {
    case 0: return f(N{}, N{}, N{});
    case 1: return f(N{}, N{}, Y{});
    case 2: return f(N{}, Y{}, N{});
    case 3: return f(N{}, Y{}, Y{});
    case 4: return f(Y{}, N{}, N{});
    case 5: return f(Y{}, N{}, Y{});
    case 6: return f(Y{}, Y{}, N{});
    default: return f(Y{}, Y{}, Y{});
  }
}

}  // namespace

void EncodePointwiseChunk(const std::vector<Item>& items, const uint8_t* records, uint32_t points,
                          std::vector<uint8_t>* out) {
  const Layout l = LayoutOf(items);
  if (points == 0) return;
  WithItems(l, [&](auto gps, auto rgb, auto bytes) {
    EncodeChunk<decltype(gps)::value, decltype(rgb)::value, decltype(bytes)::value>(l, records,
                                                                                   points, out);
  });
}

void DecodePointwiseChunk(const std::vector<Item>& items, const uint8_t* data, size_t size,
                          uint32_t points, uint8_t* out) {
  const Layout l = LayoutOf(items);
  if (points == 0) return;
  if (size < l.length) ThrowEndsEarly(size, 0);
  WithItems(l, [&](auto gps, auto rgb, auto bytes) {
    DecodeChunk<decltype(gps)::value, decltype(rgb)::value, decltype(bytes)::value>(l, data, size,
                                                                                   points, out);
  });
}

}  // namespace candi::io::laz
