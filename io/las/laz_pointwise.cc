// LASzip's pointwise chunked compressor (compressor 2), decoder side, items of version 2:
// POINT10, GPSTIME11, RGB12 and BYTE (LASzip's LASreadItemCompressed_*_v2). A chunk is its first
// record raw, then one arithmetic stream that codes every later record item by item, each
// predicted from the previous record (and, for POINT10, from contexts selected by the return
// number and the number of returns).
#include <array>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "io/las/laz_format.h"

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

inline int32_t AddWrapping(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b));
}
inline int32_t MulWrapping(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) * static_cast<uint32_t>(b));
}

// ---- POINT10 v2: x, y, z, intensity, return bits, class, scan angle, user data, source id ----

class Point10Decoder {
 public:
  explicit Point10Decoder(const uint8_t* first) {
    x_ = LoadLE<int32_t>(first);
    y_ = LoadLE<int32_t>(first + 4);
    z_ = LoadLE<int32_t>(first + 8);
    intensity_ = 0;  // LASzip predicts the second point's intensity from 0, not the first's
    bits_ = first[14];
    class_ = first[15];
    scan_angle_ = first[16];
    user_data_ = first[17];
    source_id_ = LoadLE<uint16_t>(first + 18);
    for (IntegerDecompressor* ic : {&ic_intensity_, &ic_source_id_, &ic_dx_, &ic_dy_, &ic_z_}) {
      ic->Init();
    }
  }

  void Decode(ArithmeticDecoder* dec, uint8_t* out) {
    const uint32_t changed = dec->DecodeSymbol(&changed_values_);
    if (changed != 0) DecodeAttributes(dec, changed);
    const uint32_t n = (bits_ >> 3) & 7;
    const uint32_t m = kNumberReturnMap[n][bits_ & 7];
    const uint32_t l = kNumberReturnLevel[n][bits_ & 7];
    const uint32_t single = n == 1;
    const int32_t dx = ic_dx_.Decompress(dec, x_median_[m].Get(), single);
    x_ = AddWrapping(x_, dx);
    x_median_[m].Add(dx);
    uint32_t k = ic_dx_.k();
    const int32_t dy = ic_dy_.Decompress(dec, y_median_[m].Get(), single + (k < 20 ? k & ~1u : 20));
    y_ = AddWrapping(y_, dy);
    y_median_[m].Add(dy);
    k = (ic_dx_.k() + ic_dy_.k()) / 2;
    z_ = ic_z_.Decompress(dec, last_height_[l], single + (k < 18 ? k & ~1u : 18));
    last_height_[l] = z_;
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
    if (changed & 32) bits_ = static_cast<uint8_t>(dec->DecodeSymbol(bit_byte_.At(bits_)));
    const uint32_t m = kNumberReturnMap[(bits_ >> 3) & 7][bits_ & 7];
    if (changed & 16) {
      intensity_ = static_cast<uint16_t>(
          ic_intensity_.Decompress(dec, last_intensity_[m], m < 3 ? m : 3));
      last_intensity_[m] = intensity_;
    } else {
      intensity_ = last_intensity_[m];
    }
    if (changed & 8) class_ = static_cast<uint8_t>(dec->DecodeSymbol(classification_.At(class_)));
    if (changed & 4) {
      const uint32_t delta = dec->DecodeSymbol(&scan_angle_rank_[(bits_ >> 6) & 1]);
      scan_angle_ = static_cast<uint8_t>(delta + scan_angle_);
    }
    if (changed & 2) {
      user_data_ = static_cast<uint8_t>(dec->DecodeSymbol(user_data_models_.At(user_data_)));
    }
    if (changed & 1) {
      source_id_ = static_cast<uint16_t>(ic_source_id_.Decompress(dec, source_id_));
    }
  }

  int32_t x_, y_, z_;
  uint16_t intensity_, source_id_;
  uint8_t bits_, class_, scan_angle_, user_data_;
  std::array<uint16_t, 16> last_intensity_{};
  std::array<int32_t, 8> last_height_{};
  std::array<Median5, 16> x_median_, y_median_;
  SymbolModel changed_values_{64};
  SymbolModel scan_angle_rank_[2] = {SymbolModel(256), SymbolModel(256)};
  LazyModels bit_byte_, classification_, user_data_models_;
  IntegerDecompressor ic_intensity_{16, 4}, ic_source_id_{16}, ic_dx_{32, 2}, ic_dy_{32, 22},
      ic_z_{32, 20};
};

// ---- GPSTIME11 v2: up to four interleaved time sequences, each with its last difference ----

constexpr uint32_t kGpsMulti = 500;
constexpr int32_t kGpsMultiMinus = -10;
constexpr uint32_t kGpsMultiUnchanged = kGpsMulti - kGpsMultiMinus + 1;  // 511
constexpr uint32_t kGpsMultiCodeFull = kGpsMulti - kGpsMultiMinus + 2;   // 512
constexpr uint32_t kGpsMultiTotal = kGpsMulti - kGpsMultiMinus + 6;      // 516

class GpsTime11Decoder {
 public:
  explicit GpsTime11Decoder(const uint8_t* first) {
    time_[0] = LoadLE<uint64_t>(first);
    ic_gps_time_.Init();
  }

  void Decode(ArithmeticDecoder* dec, uint8_t* out) {
    // A switch to another sequence decodes that sequence's value next; an encoder switches only
    // to a sequence it can code, so a second switch in a row means corrupt data.
    for (int switches = 0; !DecodeStep(dec); ++switches) {
      if (switches == 3) throw LazError("GPSTIME11: corrupt data (repeated sequence switches)");
    }
    StoreLE<uint64_t>(out, time_[last_]);
  }

 private:
  // Returns false when the symbol switched sequences (the value follows).
  bool DecodeStep(ArithmeticDecoder* dec) {
    if (last_diff_[last_] == 0) {
      const uint32_t multi = dec->DecodeSymbol(&zero_diff_);
      if (multi == 1) {
        last_diff_[last_] = ic_gps_time_.Decompress(dec, 0, 0);
        Advance(last_diff_[last_]);
        extreme_count_[last_] = 0;
      } else if (multi == 2) {
        StartSequence(dec);
      } else if (multi > 2) {
        last_ = (last_ + multi - 2) & 3;
        return false;
      }
      return true;
    }
    const uint32_t multi = dec->DecodeSymbol(&multi_);
    if (multi == 1) {
      Advance(ic_gps_time_.Decompress(dec, last_diff_[last_], 1));
      extreme_count_[last_] = 0;
    } else if (multi < kGpsMultiUnchanged) {
      Advance(DecodeMultipleDiff(dec, multi));
    } else if (multi == kGpsMultiCodeFull) {
      StartSequence(dec);
    } else if (multi > kGpsMultiCodeFull) {
      last_ = (last_ + multi - kGpsMultiCodeFull) & 3;
      return false;
    }
    return true;
  }

  // A difference predicted as a multiple of the last one (multi != 1, < kGpsMultiUnchanged).
  int32_t DecodeMultipleDiff(ArithmeticDecoder* dec, uint32_t multi) {
    const int32_t last = last_diff_[last_];
    int32_t diff;
    bool extreme = false;
    if (multi == 0) {
      diff = ic_gps_time_.Decompress(dec, 0, 7);
      extreme = true;
    } else if (multi < kGpsMulti) {
      diff = ic_gps_time_.Decompress(dec, MulWrapping(static_cast<int32_t>(multi), last),
                                     multi < 10 ? 2 : 3);
    } else if (multi == kGpsMulti) {
      diff = ic_gps_time_.Decompress(dec, MulWrapping(kGpsMulti, last), 4);
      extreme = true;
    } else {
      const int32_t negative = static_cast<int32_t>(kGpsMulti) - static_cast<int32_t>(multi);
      if (negative > kGpsMultiMinus) {
        diff = ic_gps_time_.Decompress(dec, MulWrapping(negative, last), 5);
      } else {
        diff = ic_gps_time_.Decompress(dec, MulWrapping(kGpsMultiMinus, last), 6);
        extreme = true;
      }
    }
    // Repeated extreme multipliers: the sequence's step changed; adopt the new difference.
    if (extreme && ++extreme_count_[last_] > 3) {
      last_diff_[last_] = diff;
      extreme_count_[last_] = 0;
    }
    return diff;
  }

  void Advance(int32_t diff) {
    time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(diff));
  }

  // A new sequence: the high 32 bits predicted from the current sequence's, the low ones raw.
  void StartSequence(ArithmeticDecoder* dec) {
    next_ = (next_ + 1) & 3;
    const int32_t high =
        ic_gps_time_.Decompress(dec, static_cast<int32_t>(time_[last_] >> 32), 8);
    time_[next_] = static_cast<uint64_t>(static_cast<uint32_t>(high)) << 32 | dec->ReadInt();
    last_ = next_;
    last_diff_[last_] = 0;
    extreme_count_[last_] = 0;
  }

  uint32_t last_ = 0, next_ = 0;
  std::array<uint64_t, 4> time_{};  // the doubles' bit patterns
  std::array<int32_t, 4> last_diff_{};
  std::array<int32_t, 4> extreme_count_{};
  SymbolModel multi_{kGpsMultiTotal}, zero_diff_{6};
  IntegerDecompressor ic_gps_time_{32, 9};
};

// ---- RGB12 v2: low and high bytes of red coded against the last, green and blue against red ----

inline uint8_t ClampU8(int32_t v) { return v <= 0 ? 0 : v >= 255 ? 255 : static_cast<uint8_t>(v); }

class Rgb12Decoder {
 public:
  explicit Rgb12Decoder(const uint8_t* first) {
    for (int c = 0; c < 3; ++c) last_[c] = LoadLE<uint16_t>(first + 2 * c);
  }

  void Decode(ArithmeticDecoder* dec, uint8_t* out) {
    const uint32_t sym = dec->DecodeSymbol(&byte_used_);
    uint16_t rgb[3];
    rgb[0] = Byte(dec, sym & 1, 0, last_[0] & 0xFF, 0);  // two statements: decoding order
    rgb[0] |= Byte(dec, sym & 2, 1, last_[0] >> 8, 0) << 8;
    if (sym & 64) {
      int32_t diff = (rgb[0] & 0xFF) - (last_[0] & 0xFF);
      rgb[1] = Byte(dec, sym & 4, 2, last_[1] & 0xFF, ClampU8(diff + (last_[1] & 0xFF)));
      diff = (diff + (rgb[1] & 0xFF) - (last_[1] & 0xFF)) / 2;
      rgb[2] = Byte(dec, sym & 16, 4, last_[2] & 0xFF, ClampU8(diff + (last_[2] & 0xFF)));
      diff = (rgb[0] >> 8) - (last_[0] >> 8);
      rgb[1] |= Byte(dec, sym & 8, 3, last_[1] >> 8, ClampU8(diff + (last_[1] >> 8))) << 8;
      diff = (diff + (rgb[1] >> 8) - (last_[1] >> 8)) / 2;
      rgb[2] |= Byte(dec, sym & 32, 5, last_[2] >> 8, ClampU8(diff + (last_[2] >> 8))) << 8;
    } else {
      rgb[1] = rgb[2] = rgb[0];  // grey
    }
    for (int c = 0; c < 3; ++c) {
      last_[c] = rgb[c];
      StoreLE<uint16_t>(out + 2 * c, rgb[c]);
    }
  }

 private:
  // One byte: when `coded`, the prediction plus a corrector from model `model` (the prediction
  // of red is its last value, that of green and blue the clamped red-corrected one); else kept.
  uint16_t Byte(ArithmeticDecoder* dec, uint32_t coded, int model, uint32_t kept,
                uint32_t prediction) {
    if (!coded) return static_cast<uint16_t>(kept);
    if (model < 2) prediction = kept;
    return static_cast<uint8_t>(dec->DecodeSymbol(&diff_[model]) + prediction);
  }

  uint16_t last_[3];
  SymbolModel byte_used_{128};
  SymbolModel diff_[6] = {SymbolModel(256), SymbolModel(256), SymbolModel(256),
                          SymbolModel(256), SymbolModel(256), SymbolModel(256)};
};

// ---- BYTE v2: each extra byte coded against the same byte of the last record ----

class ByteDecoder {
 public:
  ByteDecoder(const uint8_t* first, size_t count)
      : last_(first, first + count), models_(count, SymbolModel(256)) {}

  void Decode(ArithmeticDecoder* dec, uint8_t* out) {
    for (size_t i = 0; i < last_.size(); ++i) {
      last_[i] = static_cast<uint8_t>(last_[i] + dec->DecodeSymbol(&models_[i]));
      out[i] = last_[i];
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

// Decoders created once per chunk; the item set is a template parameter, so the per-point loop
// has no branches on the item types.
template <bool kGps, bool kRgb, bool kBytes>
void DecodeChunk(const Layout& l, const uint8_t* data, size_t size, uint32_t points,
                 uint8_t* out) {
  std::memcpy(out, data, l.length);
  if (points == 1) return;
  Point10Decoder point(out);
  std::unique_ptr<GpsTime11Decoder> gps;
  std::unique_ptr<Rgb12Decoder> rgb;
  std::unique_ptr<ByteDecoder> bytes;
  if (kGps) gps = std::make_unique<GpsTime11Decoder>(out + l.gps);
  if (kRgb) rgb = std::make_unique<Rgb12Decoder>(out + l.rgb);
  if (kBytes) bytes = std::make_unique<ByteDecoder>(out + l.bytes, l.byte_count);
  ArithmeticDecoder dec;
  dec.Init(data + l.length, data + size);
  uint8_t* record = out;
  for (uint32_t i = 1; i < points; ++i) {
    record += l.length;
    point.Decode(&dec, record);
    if constexpr (kGps) gps->Decode(&dec, record + l.gps);
    if constexpr (kRgb) rgb->Decode(&dec, record + l.rgb);
    if constexpr (kBytes) bytes->Decode(&dec, record + l.bytes);
    if ((i & 4095) == 0 && dec.overrun()) ThrowEndsEarly(size, i);  // stop early on truncation
  }
  if (dec.overrun()) ThrowEndsEarly(size, points - 1);
}

}  // namespace

void DecodePointwiseChunk(const std::vector<Item>& items, const uint8_t* data, size_t size,
                          uint32_t points, uint8_t* out) {
  const Layout l = LayoutOf(items);
  if (points == 0) return;
  if (size < l.length) ThrowEndsEarly(size, 0);
  const int variant = (l.gps >= 0 ? 4 : 0) | (l.rgb >= 0 ? 2 : 0) | (l.bytes >= 0 ? 1 : 0);
  switch (variant) {
    case 0: return DecodeChunk<false, false, false>(l, data, size, points, out);
    case 1: return DecodeChunk<false, false, true>(l, data, size, points, out);
    case 2: return DecodeChunk<false, true, false>(l, data, size, points, out);
    case 3: return DecodeChunk<false, true, true>(l, data, size, points, out);
    case 4: return DecodeChunk<true, false, false>(l, data, size, points, out);
    case 5: return DecodeChunk<true, false, true>(l, data, size, points, out);
    case 6: return DecodeChunk<true, true, false>(l, data, size, points, out);
    default: return DecodeChunk<true, true, true>(l, data, size, points, out);
  }
}

}  // namespace candi::io::laz
