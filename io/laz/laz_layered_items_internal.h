// Private to io/laz/laz_layered.cc and laz_layered_encode.cc: the per-item decoders and encoders
// of LASzip's layered chunked compressor (items of version 3), and what both directions share.
//
// Each decoder is made for one chunk: Start() takes the raw first record (already copied to the
// output) and the item's layers, Decode() fills the next record. They decode as LASzip's
// lasreaditemcompressed_v3.cpp (and as its writer, for NIR). Records are written little-endian,
// LAS 1.4 layout:
//   POINT14 (30 bytes): X, Y, Z int32; intensity uint16; return number (bits 0-3) and number of
//     returns (4-7); classification flags (0-3), scanner channel (4-5), scan direction (6), edge
//     of flight line (7); classification; user data; scan angle int16; point source uint16; GPS
//     time float64.
//   RGB14: red, green, blue uint16; RGBNIR14: the same then NIR uint16; BYTE14: the extra bytes.
// Corrupt input never reads outside the layers (the arithmetic decoder yields zeros past a
// layer's end and flags overrun(), reported by OverrunLayer()); values are then garbage but all
// model and table indices stay in range. Not thread-safe; one decoder per chunk.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "io/laz/laz_arith.h"
#include "io/laz/laz_color_internal.h"
#include "io/laz/laz_format.h"
#include "io/laz/laz_gps_time_internal.h"

namespace candi::io::laz::layered {

// Where POINT14's companions are: their item index and record offset (-1: absent); at most one
// of each kind. ItemSetOf checks the items (LazError naming a bad one).
struct ItemSet {
  size_t record = 0;  // record bytes
  int color = -1, extra = -1;
  size_t color_offset = 0, extra_offset = 0;
  bool nir = false;
  uint32_t extra_count = 0;
};
ItemSet ItemSetOf(const std::vector<Item>& items);

// One layer's bytes inside the chunk.
struct LayerSpan {
  const uint8_t* data = nullptr;
  uint32_t size = 0;
};

// Starts `decoder` on a non-empty layer; returns whether the layer is in use.
inline bool StartLayer(const LayerSpan& span, ArithmeticDecoder* decoder) {
  if (span.size == 0) return false;
  decoder->Init(span.data, span.data + span.size);
  return true;
}

inline uint16_t LoadU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | p[1] << 8); }
inline void StoreU16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
inline uint32_t LoadU32(const uint8_t* p) {
  return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
}
inline void StoreU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
inline uint64_t LoadU64(const uint8_t* p) {
  return uint64_t{LoadU32(p)} | uint64_t{LoadU32(p + 4)} << 32;
}
inline void StoreU64(uint8_t* p, uint64_t v) {
  StoreU32(p, static_cast<uint32_t>(v));
  StoreU32(p + 4, static_cast<uint32_t>(v >> 32));
}

// LASzip's context of a point's return map (number of returns n, return number r): 6 classes.
inline constexpr uint8_t kReturnMap6[16][16] = {
    {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5},
    {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
    {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3},
    {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
    {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
    {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5},
    {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};

// LASzip's "return level" context: |n - r| capped at 7 (its number_return_level_8ctx table).
inline uint32_t ReturnLevel(uint32_t n, uint32_t r) {
  return std::min<uint32_t>(n > r ? n - r : r - n, 7);
}

inline uint32_t EvenCapped(uint32_t k, uint32_t cap) { return k < cap ? (k & ~1u) : cap; }

// A model created on first use, as LASzip does for its sparse context tables (most of the 64
// classification contexts never occur, and 256-symbol models are not free to build).
inline SymbolModel* LazyModel(std::unique_ptr<SymbolModel>* slot, uint32_t symbols) {
  if (!*slot) *slot = std::make_unique<SymbolModel>(symbols);
  return slot->get();
}

// ---------------------------------------------------------------------------------------------
// POINT14

// The fields of a LAS 1.4 point as POINT14 predicts them.
struct Point14 {
  int32_t x = 0, y = 0, z = 0;
  uint16_t intensity = 0;
  uint8_t return_number = 0, number_of_returns = 0;
  uint8_t classification_flags = 0, scanner_channel = 0;
  uint8_t scan_direction = 0, edge_of_flight_line = 0;
  uint8_t classification = 0, user_data = 0;
  int16_t scan_angle = 0;
  uint16_t point_source = 0;
  uint64_t gps_time = 0;  // the float64's bits; LASzip predicts them as integers
  bool gps_time_change = false;
};

inline Point14 UnpackPoint14(const uint8_t* p) {
  Point14 q;
  q.x = static_cast<int32_t>(LoadU32(p));
  q.y = static_cast<int32_t>(LoadU32(p + 4));
  q.z = static_cast<int32_t>(LoadU32(p + 8));
  q.intensity = LoadU16(p + 12);
  q.return_number = p[14] & 15;
  q.number_of_returns = p[14] >> 4;
  q.classification_flags = p[15] & 15;
  q.scanner_channel = (p[15] >> 4) & 3;
  q.scan_direction = (p[15] >> 6) & 1;
  q.edge_of_flight_line = p[15] >> 7;
  q.classification = p[16];
  q.user_data = p[17];
  q.scan_angle = static_cast<int16_t>(LoadU16(p + 18));
  q.point_source = LoadU16(p + 20);
  q.gps_time = LoadU64(p + 22);
  return q;
}

inline void PackPoint14(const Point14& q, uint8_t* p) {
  StoreU32(p, static_cast<uint32_t>(q.x));
  StoreU32(p + 4, static_cast<uint32_t>(q.y));
  StoreU32(p + 8, static_cast<uint32_t>(q.z));
  StoreU16(p + 12, q.intensity);
  p[14] = static_cast<uint8_t>(q.return_number | q.number_of_returns << 4);
  p[15] = static_cast<uint8_t>(q.classification_flags | q.scanner_channel << 4 |
                               q.scan_direction << 6 | q.edge_of_flight_line << 7);
  p[16] = q.classification;
  p[17] = q.user_data;
  StoreU16(p + 18, static_cast<uint16_t>(q.scan_angle));
  StoreU16(p + 20, q.point_source);
  StoreU64(p + 22, q.gps_time);
}

// The nine POINT14 layers in stream order.
enum Point14Layer {
  kXY,
  kZ,
  kClass,
  kFlags,
  kIntensity,
  kScanAngle,
  kUserData,
  kSource,
  kGps,
  kPoint14Layers
};

// Everything POINT14 keeps per scanner channel. Models of layers the chunk does not use are not
// built: with small chunks (COPC) building models costs more than decoding.
struct Point14Context {
  Point14Context(const Point14& seed, const std::array<bool, kPoint14Layers>& active) : last(seed) {
    last.gps_time_change = false;
    dx.Init();
    dy.Init();
    if (active[kZ]) z.Init();
    if (active[kIntensity]) intensity.Init();
    if (active[kScanAngle]) scan_angle.Init();
    if (active[kSource]) point_source.Init();
    if (active[kGps]) {
      gps_time.Init();
      gps_multi = std::make_unique<SymbolModel>(515);
      gps_no_diff = std::make_unique<SymbolModel>(5);
    }
    last_z.fill(seed.z);
    last_intensity.fill(seed.intensity);
    gps.time[0] = seed.gps_time;
  }
  Point14 last;
  // channel/returns/XY layer
  std::vector<SymbolModel> changed_values = std::vector<SymbolModel>(8, SymbolModel(128));
  SymbolModel scanner_channel{3};
  std::array<std::unique_ptr<SymbolModel>, 16> number_of_returns, return_number;
  SymbolModel return_number_gps_same{13};
  IntegerCoder dx{32, 2}, dy{32, 22};
  std::array<Median5, 12> x_diff_median, y_diff_median;
  // the other layers
  IntegerCoder z{32, 20};
  std::array<int32_t, 8> last_z{};
  std::array<std::unique_ptr<SymbolModel>, 64> classification, flags, user_data;
  IntegerCoder intensity{16, 4};
  std::array<uint16_t, 8> last_intensity{};
  IntegerCoder scan_angle{16, 2};
  IntegerCoder point_source{16};
  std::unique_ptr<SymbolModel> gps_multi, gps_no_diff;
  IntegerCoder gps_time{32, 9};
  GpsSequences gps;
};

class Point14Decoder {
 public:
  // Starts the chunk from its raw first record and the 9 layers; returns its scanner channel,
  // the context of the other items' Start().
  uint32_t Start(const uint8_t* first, const LayerSpan* layers);
  // Decodes the next record into `out` (30 bytes); returns the context of the other items'
  // Decode(): the new scanner channel when it changed at this point, else 0 (LASzip quirk).
  uint32_t Decode(uint8_t* out);
  // The first layer whose decoder overran its bytes, or -1.
  int OverrunLayer() const;

 private:
  Point14Context* SwitchChannel(Point14Context* from);
  void DecodeReturns(Point14Context* c, uint32_t changed, bool gps_change);
  void DecodeXYZ(Point14Context* c, bool gps_change);
  void DecodeAttributes(Point14Context* c, uint32_t changed, bool gps_change);
  void DecodeGpsTime(Point14Context* c);
  int32_t DecodeGpsDiff(Point14Context* c, uint32_t multi);
  void NewGpsSequence(Point14Context* c);

  std::array<ArithmeticDecoder, kPoint14Layers> dec_;
  std::array<bool, kPoint14Layers> active_{};
  std::array<std::unique_ptr<Point14Context>, 4> contexts_;
  uint32_t current_ = 0;
};

// ---------------------------------------------------------------------------------------------
// RGB14 / RGBNIR14 and BYTE14

// The per-channel state of the colour and extra-bytes items, for both directions.
struct ColorContext {
  bool used = false;
  std::array<uint16_t, 4> last{};  // red, green, blue, NIR
  std::unique_ptr<RgbModels> rgb;
  std::unique_ptr<NirModels> nir;
};
struct ByteContext {
  bool used = false;
  std::vector<uint8_t> last;
  std::vector<SymbolModel> models;
};

// Follows POINT14's context (the scanner channel when it changed at this point, else 0) and
// returns the context whose `last` the item predicts from and updates. LASzip quirk: only a
// context's first use re-seeds it (init(new context, previous context)); back on a context seen
// before, the item keeps predicting from the previous context's last values, with the models of
// the context it switched to.
template <class Context, class Init>
Context* FollowContext(std::array<Context, 4>* contexts, uint32_t* current, uint32_t context,
                       Init init) {
  Context* last = &(*contexts)[*current];
  if (context != *current) {
    *current = context;
    if (!(*contexts)[context].used) {
      init(&(*contexts)[context], *last);
      last = &(*contexts)[context];
    }
  }
  return last;
}

class ColorDecoder {
 public:
  explicit ColorDecoder(bool nir) : nir_(nir) {}
  // Starts from the raw first colour (6 or 8 bytes) and the item's 1 or 2 layers. `context`:
  // what Point14Decoder::Start/Decode returned for the record.
  void Start(const uint8_t* first, const LayerSpan* layers, uint32_t context);
  void Decode(uint8_t* out, uint32_t context);
  int OverrunLayer() const;

 private:
  void InitContext(ColorContext* c, const uint16_t* seed) const;
  bool nir_;
  ArithmeticDecoder rgb_dec_, nir_dec_;
  bool rgb_active_ = false, nir_active_ = false;
  std::array<ColorContext, 4> contexts_;
  uint32_t current_ = 0;
};

class ByteDecoder {
 public:
  explicit ByteDecoder(uint32_t count) : count_(count), dec_(count), active_(count) {}
  // Starts from the raw first extra bytes and the item's `count` layers.
  void Start(const uint8_t* first, const LayerSpan* layers, uint32_t context);
  void Decode(uint8_t* out, uint32_t context);
  int OverrunLayer() const;

 private:
  void InitContext(ByteContext* c, const uint8_t* seed) const;
  uint32_t count_;
  std::vector<ArithmeticDecoder> dec_;
  std::vector<uint8_t> active_;
  std::array<ByteContext, 4> contexts_;
  uint32_t current_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Encoders: the inverse of the decoders above (LASzip's laswriteitemcompressed_v3.cpp). Each
// codes a chunk's records after the first into its layers; Finish() ends the layers and appends
// their sizes (uint32 LE each) to `sizes` and their bytes to `bytes`. A layer whose field never
// changed in the chunk is stored with size 0 (the decoder then keeps the field), except POINT14's
// XY and Z layers, which are always stored.

// A layer whose field is the same in every record of the chunk is stored empty whatever it codes,
// so its coding can be skipped: `coded` says which layers to code (POINT14's classification,
// flags, intensity and user data layers, the colour's RGB and NIR layers; the others are coded
// as their changes require).
class Point14Encoder {
 public:
  // Starts the chunk from its first record; returns its scanner channel, the other items' context.
  uint32_t Start(const uint8_t* first, const std::array<bool, kPoint14Layers>& coded);
  // Codes the next record (30 bytes); returns the other items' context as Point14Decoder::Decode.
  uint32_t Encode(const uint8_t* record);
  void Finish(std::vector<uint8_t>* sizes, std::vector<uint8_t>* bytes);

 private:
  void EncodeReturns(Point14Context* c, const Point14& p, uint32_t changed, bool gps_change);
  void EncodeXYZ(Point14Context* c, const Point14& p, bool gps_change);
  void EncodeAttributes(Point14Context* c, const Point14& p, bool angle_change,
                        bool source_change, bool gps_change);

  std::array<ArithmeticEncoder, kPoint14Layers> enc_;
  std::array<bool, kPoint14Layers> changed_{}, coded_{};
  std::array<std::unique_ptr<Point14Context>, 4> contexts_;
  uint32_t current_ = 0;
};

// RGB14 (nir false) or RGBNIR14, started from the chunk's first colour and POINT14's context;
// code_rgb, code_nir: whether to code each layer (as Point14Encoder's `coded`).
class ColorEncoder {
 public:
  ColorEncoder(bool nir, const uint8_t* first, uint32_t context, bool code_rgb, bool code_nir);
  void Encode(const uint8_t* item, uint32_t context);
  void Finish(std::vector<uint8_t>* sizes, std::vector<uint8_t>* bytes);

 private:
  bool nir_, code_rgb_, code_nir_;
  bool rgb_changed_ = false, nir_changed_ = false;  // a layer is stored only when it changed
  ArithmeticEncoder rgb_enc_, nir_enc_;
  std::array<ColorContext, 4> contexts_;
  uint32_t current_;
};

// BYTE14 of `count` bytes a record, started as ColorEncoder.
class ByteEncoder {
 public:
  ByteEncoder(uint32_t count, const uint8_t* first, uint32_t context);
  void Encode(const uint8_t* item, uint32_t context);
  void Finish(std::vector<uint8_t>* sizes, std::vector<uint8_t>* bytes);

 private:
  std::vector<ArithmeticEncoder> enc_;
  std::vector<uint8_t> changed_;  // per byte, as ColorEncoder's flags
  std::array<ByteContext, 4> contexts_;
  uint32_t current_;
};

}  // namespace candi::io::laz::layered
