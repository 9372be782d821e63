#include "io/laz/laz_gps_time_internal.h"

#include <cstdint>

namespace candi::io::laz {

namespace {

constexpr int32_t kMulti = 500;       // LASZIP_GPSTIME_MULTI
constexpr int32_t kMultiMinus = -10;  // LASZIP_GPSTIME_MULTI_MINUS
constexpr uint32_t kMultiFull = 511;  // the multi model's "new sequence" code in v3 (512 in v2)

int32_t WrapMul(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) * static_cast<uint32_t>(b));
}

bool Fits32(int64_t v) { return v == static_cast<int32_t>(v); }

// LASzip's multiplier: I32_QUANTIZE((F32)diff / (F32)last), in float32 as LASzip computes it. A
// quotient outside int32 converts to INT32_MIN, as LASzip's cast does on x86 (a rare case of
// huge jumps: any value decodes, only the compression changes).
int32_t Multiplier(int32_t diff, int32_t last) {
  const float f = static_cast<float>(diff) / static_cast<float>(last);
  const float r = f >= 0 ? f + 0.5f : f - 0.5f;
  if (!(r >= -2147483648.0f && r < 2147483648.0f)) return INT32_MIN;
  return static_cast<int32_t>(r);
}

// A difference that fits 32 bits while the last one is not 0: coded against a multiple of it.
void EncodeMultipleDiff(ArithmeticEncoder* enc, const GpsTimeModels& m, int32_t diff,
                        GpsSequences* g) {
  int32_t& last = g->diff[g->last];
  int32_t& extreme = g->extreme_count[g->last];
  const int32_t multi = Multiplier(diff, last);
  // Repeated extreme multipliers: the sequence's step changed; adopt the new difference.
  auto count_extreme = [&] {
    if (++extreme > 3) last = diff, extreme = 0;
  };
  if (multi == 1) {
    enc->EncodeSymbol(m.multi, 1);
    m.ic->Compress(enc, last, diff, 1);
    extreme = 0;
  } else if (multi > 0 && multi < kMulti) {
    enc->EncodeSymbol(m.multi, static_cast<uint32_t>(multi));
    m.ic->Compress(enc, WrapMul(multi, last), diff, multi < 10 ? 2 : 3);
  } else if (multi >= kMulti) {
    enc->EncodeSymbol(m.multi, kMulti);
    m.ic->Compress(enc, WrapMul(kMulti, last), diff, 4);
    count_extreme();
  } else if (multi < 0 && multi > kMultiMinus) {
    enc->EncodeSymbol(m.multi, static_cast<uint32_t>(kMulti - multi));
    m.ic->Compress(enc, WrapMul(multi, last), diff, 5);
  } else if (multi < 0) {
    enc->EncodeSymbol(m.multi, static_cast<uint32_t>(kMulti - kMultiMinus));
    m.ic->Compress(enc, WrapMul(kMultiMinus, last), diff, 6);
    count_extreme();
  } else {
    enc->EncodeSymbol(m.multi, 0);
    m.ic->Compress(enc, 0, diff, 7);
    count_extreme();
  }
}

}  // namespace

void EncodeGpsTime(ArithmeticEncoder* enc, const GpsTimeModels& m, uint64_t time, GpsSequences* g) {
  const uint32_t shift = m.unchanged_codes ? 1 : 0;
  for (;;) {  // at most one switch to another sequence, then the time is coded there
    const uint64_t last_time = g->time[g->last];
    const bool zero = g->diff[g->last] == 0;
    if (m.unchanged_codes && time == last_time) {
      enc->EncodeSymbol(zero ? m.zero_diff : m.multi, zero ? 0 : kMultiFull);
      return;
    }
    SymbolModel* model = zero ? m.zero_diff : m.multi;
    const uint32_t full = zero ? shift + 1 : kMultiFull + shift;
    const int64_t diff = static_cast<int64_t>(time - last_time);
    if (Fits32(diff)) {
      if (zero) {
        enc->EncodeSymbol(m.zero_diff, shift);
        m.ic->Compress(enc, 0, static_cast<int32_t>(diff), 0);
        g->diff[g->last] = static_cast<int32_t>(diff);
        g->extreme_count[g->last] = 0;
      } else {
        EncodeMultipleDiff(enc, m, static_cast<int32_t>(diff), g);
      }
      g->time[g->last] = time;
      return;
    }
    uint32_t other = 1;
    while (other < 4 && !Fits32(static_cast<int64_t>(time - g->time[(g->last + other) & 3]))) {
      ++other;
    }
    if (other < 4) {  // the time belongs to another sequence: switch, then code it there
      enc->EncodeSymbol(model, full + other);
      g->last = (g->last + other) & 3;
      continue;
    }
    enc->EncodeSymbol(model, full);  // a new sequence
    m.ic->Compress(enc, static_cast<int32_t>(static_cast<uint32_t>(last_time >> 32)),
                   static_cast<int32_t>(static_cast<uint32_t>(time >> 32)), 8);
    enc->WriteInt(static_cast<uint32_t>(time));
    g->next = (g->next + 1) & 3;
    g->last = g->next;
    g->diff[g->last] = 0;
    g->extreme_count[g->last] = 0;
    g->time[g->last] = time;
    return;
  }
}

}  // namespace candi::io::laz
