// The entropy coder of LASzip-compressed LAS (LAZ): an adaptive arithmetic decoder and encoder
// sharing their bit and symbol models, and the integer coder that codes a corrector against a
// prediction (LASzip's "IntegerCompressor": k-bit class symbol, then the low bits raw), both ways.
// The encoder is the exact inverse of the decoder: the same models see the same symbols in the
// same order, so a stream the encoder writes decodes to its input, and (as LASzip's encoder does)
// it ends a stream with the bytes that let the decoder read its 4-byte look-ahead.
//
// Pure byte-level coding, no file access. The decoder reads only inside [begin, end): reading
// past `end` yields zero bytes and sets overrun(), which the chunk decoders report as a corrupt
// chunk (so truncated or bit-flipped input can never read out of bounds). Models and decoders
// are not thread-safe; each chunk gets its own.
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace candi::io::laz {

// A corrupt or unsupported compressed stream. The LAZ reader adds the file and byte offset.
struct LazError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Adaptive binary model (LASzip ArithmeticBitModel).
class BitModel {
 public:
  BitModel();
  void Reset();

 private:
  friend class ArithmeticDecoder;
  friend class ArithmeticEncoder;
  void Update();
  uint32_t update_cycle_ = 0, bits_until_update_ = 0;
  uint32_t bit_0_prob_ = 0, bit_0_count_ = 0, bit_count_ = 0;
};

// Adaptive model of `symbols` (2..2048) symbols (LASzip ArithmeticModel); CANDI_CHECK on a bad
// count. The initial (equiprobable) distribution is made at the model's first symbol, not when
// it is constructed or reset: a chunk's coders hold hundreds of models, most of which (the
// integer coders' classes of large correctors) a chunk never uses.
class SymbolModel {
 public:
  explicit SymbolModel(uint32_t symbols);
  // Back to the initial distribution (made at the next symbol). Keeps the storage.
  void Reset() { distribution_.clear(); }
  uint32_t symbols() const { return symbols_; }

 private:
  friend class ArithmeticDecoder;
  friend class ArithmeticEncoder;
  // The initial distribution (LASzip ArithmeticModel::init), with the decoder's table or not.
  void Start(bool with_table);
  // New distribution from the counts; with_table: also the decoder's table (an encoder never
  // reads it).
  void Update(bool with_table = true);
  uint32_t symbols_, last_symbol_, table_size_, table_shift_;
  uint32_t total_count_ = 0, update_cycle_ = 0, symbols_until_update_ = 0;
  // distribution_ (symbols_; empty until the first symbol after construction or Reset),
  // symbol_count_ (symbols_), decoder_table_ (table_size_ + 2 in a decoder when symbols_ > 16,
  // else empty).
  std::vector<uint32_t> distribution_, symbol_count_, decoder_table_;
};

class ArithmeticDecoder {
 public:
  // Starts decoding [begin, end): reads the 4 initial bytes.
  void Init(const uint8_t* begin, const uint8_t* end);
  uint32_t DecodeBit(BitModel* model);
  uint32_t DecodeSymbol(SymbolModel* model);
  uint32_t ReadBits(uint32_t bits);  // 1..32 raw bits
  uint8_t ReadByte();
  uint16_t ReadShort();
  uint32_t ReadInt();
  uint64_t ReadInt64();
  // True once the decoder needed bytes beyond `end`.
  bool overrun() const { return overrun_; }
  // Bytes of [begin, end) consumed so far.
  size_t consumed() const { return static_cast<size_t>(next_ - begin_); }

 private:
  uint8_t NextByte();
  void Renormalize();
  const uint8_t *begin_ = nullptr, *next_ = nullptr, *end_ = nullptr;
  uint32_t value_ = 0, length_ = 0;
  bool overrun_ = false;
};

// Writes an arithmetic-coded stream into a growing byte buffer (LASzip ArithmeticEncoder). A carry
// is propagated back through the bytes already written, so the buffer holds the whole stream.
class ArithmeticEncoder {
 public:
  ArithmeticEncoder() { Init(); }
  // Starts a new stream, dropping any bytes of the last one.
  void Init();
  void EncodeBit(BitModel* model, uint32_t bit);
  void EncodeSymbol(SymbolModel* model, uint32_t symbol);  // symbol < model->symbols()
  void WriteBits(uint32_t bits, uint32_t value);           // 1..32 raw bits
  void WriteByte(uint8_t value) { WriteRaw(8, value); }
  void WriteShort(uint16_t value) { WriteRaw(16, value); }
  void WriteInt(uint32_t value);
  void WriteInt64(uint64_t value);
  // Ends the stream (LASzip done(): the interval's final bytes, then two or three zero bytes).
  void Done();
  // The stream, after Done().
  const uint8_t* data() const { return out_.data(); }
  size_t size() const { return used_; }

 private:
  void WriteRaw(uint32_t bits, uint32_t value);  // bits <= 16
  void PropagateCarry();
  void Renormalize();
  void Grow();  // makes room for at least one more byte after the used_ ones
  // The stream is the first used_ bytes of out_, whose size only grows, so that its storage
  // serves stream after stream. The byte stores may alias any member, so Renormalize works on
  // copies in locals.
  std::vector<uint8_t> out_;
  size_t used_ = 0;
  uint32_t base_ = 0, length_ = 0;
};

// Codes integers as corrections of a prediction (LASzip IntegerCompressor), both ways: one set
// of models, which an object uses either to compress or to decompress a stream. bits: the
// integer's width (1..32); contexts: independent model sets; bits_high: the class threshold
// above which low bits are coded raw; range: the value range (0: 2^bits).
class IntegerCoder {
 public:
  IntegerCoder(uint32_t bits = 16, uint32_t contexts = 1, uint32_t bits_high = 8,
               uint32_t range = 0);
  // (Re)creates the models; call before the first Compress/Decompress of a chunk.
  void Init();
  int32_t Decompress(ArithmeticDecoder* decoder, int32_t prediction, uint32_t context = 0);
  void Compress(ArithmeticEncoder* encoder, int32_t prediction, int32_t real,
                uint32_t context = 0);
  // k (the corrector's class) of the last Compress or Decompress.
  uint32_t k() const { return k_; }

 private:
  int32_t ReadCorrector(ArithmeticDecoder* decoder, SymbolModel* model);
  void WriteCorrector(ArithmeticEncoder* encoder, int32_t corrector, SymbolModel* model);
  uint32_t bits_, contexts_, bits_high_, range_;
  uint32_t corr_bits_, corr_range_;
  int32_t corr_min_, corr_max_;
  uint32_t k_ = 0;
  std::vector<SymbolModel> m_bits_;
  BitModel m_corrector0_;                 // class 0 (LASzip shares it between contexts)
  std::vector<SymbolModel> m_corrector_;  // classes 1..corr_bits_ (index k - 1)
};

// LASzip adds and multiplies int32 predictions with two's-complement wrap-around.
inline int32_t WrapAdd(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b));
}
inline int32_t WrapSub(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) - static_cast<uint32_t>(b));
}
inline int32_t WrapMul(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) * static_cast<uint32_t>(b));
}

// ---- Hot paths, inline (a chunk decodes millions of symbols). ----

namespace arith_internal {
constexpr uint32_t kMinLength = 0x01000000u;  // renormalise below this interval length
constexpr uint32_t kBitLengthShift = 13;      // BitModel probabilities: 13 bits
constexpr uint32_t kSymbolLengthShift = 15;   // SymbolModel distributions: 15 bits
}  // namespace arith_internal

inline uint8_t ArithmeticDecoder::NextByte() {
  if (__builtin_expect(next_ < end_, 1)) return *next_++;
  overrun_ = true;
  return 0;
}

inline void ArithmeticDecoder::Renormalize() {
  do {
    value_ = (value_ << 8) | NextByte();
  } while ((length_ <<= 8) < arith_internal::kMinLength);
}

inline uint32_t ArithmeticDecoder::DecodeBit(BitModel* m) {
  const uint32_t x = m->bit_0_prob_ * (length_ >> arith_internal::kBitLengthShift);
  const uint32_t bit = value_ >= x;
  if (bit == 0) {
    length_ = x;
    ++m->bit_0_count_;
  } else {
    value_ -= x;
    length_ -= x;
  }
  if (length_ < arith_internal::kMinLength) Renormalize();
  if (__builtin_expect(--m->bits_until_update_ == 0, 0)) m->Update();
  return bit;
}

inline uint32_t ArithmeticDecoder::DecodeSymbol(SymbolModel* m) {
  if (__builtin_expect(m->distribution_.empty(), 0)) m->Start(true);
  const uint32_t* dist = m->distribution_.data();
  uint32_t sym, x, y = length_;
  if (!m->decoder_table_.empty()) {
    length_ >>= arith_internal::kSymbolLengthShift;
    const uint32_t dv = value_ / length_;
    uint32_t t = dv >> m->table_shift_;
    if (t > m->table_size_) t = m->table_size_;  // only a corrupt stream gets here
    const uint32_t* table = m->decoder_table_.data();
    sym = table[t];
    uint32_t n = table[t + 1] + 1;
    while (n > sym + 1) {  // bisection within the table's bracket
      const uint32_t k = (sym + n) >> 1;
      if (dist[k] > dv) {
        n = k;
      } else {
        sym = k;
      }
    }
    x = dist[sym] * length_;
    if (sym != m->last_symbol_) y = dist[sym + 1] * length_;
  } else {
    x = sym = 0;
    length_ >>= arith_internal::kSymbolLengthShift;
    uint32_t n = m->symbols_;
    uint32_t k = n >> 1;
    do {
      const uint32_t z = length_ * dist[k];
      if (z > value_) {
        n = k;
        y = z;
      } else {
        sym = k;
        x = z;
      }
    } while ((k = (sym + n) >> 1) != sym);
  }
  value_ -= x;
  length_ = y - x;
  if (length_ < arith_internal::kMinLength) Renormalize();
  ++m->symbol_count_[sym];
  if (__builtin_expect(--m->symbols_until_update_ == 0, 0)) m->Update();
  return sym;
}

inline uint32_t ArithmeticDecoder::ReadBits(uint32_t bits) {
  if (bits > 19) {
    const uint32_t low = ReadShort();
    const uint32_t high = ReadBits(bits - 16);
    return (high << 16) | low;
  }
  const uint32_t sym = value_ / (length_ >>= bits);
  value_ -= length_ * sym;
  if (length_ < arith_internal::kMinLength) Renormalize();
  return sym;
}

inline uint8_t ArithmeticDecoder::ReadByte() {
  const uint32_t sym = value_ / (length_ >>= 8);
  value_ -= length_ * sym;
  if (length_ < arith_internal::kMinLength) Renormalize();
  return static_cast<uint8_t>(sym);
}

inline uint16_t ArithmeticDecoder::ReadShort() {
  const uint32_t sym = value_ / (length_ >>= 16);
  value_ -= length_ * sym;
  if (length_ < arith_internal::kMinLength) Renormalize();
  return static_cast<uint16_t>(sym);
}

inline uint32_t ArithmeticDecoder::ReadInt() {
  const uint32_t low = ReadShort();
  const uint32_t high = ReadShort();
  return (high << 16) | low;
}

inline uint64_t ArithmeticDecoder::ReadInt64() {
  const uint64_t low = ReadInt();
  const uint64_t high = ReadInt();
  return (high << 32) | low;
}

inline void ArithmeticEncoder::PropagateCarry() {
  // The carry runs back over 0xFF bytes; a stream's first byte never overflows (base < 2^32).
  uint8_t* const first = out_.data();
  for (uint8_t* p = first + used_; p-- != first;) {
    if (++*p != 0) return;
  }
}

inline void ArithmeticEncoder::Renormalize() {
  uint32_t base = base_, length = length_;
  // At most 3 bytes (length >= 1 after a symbol); Grow() leaves room for them.
  if (__builtin_expect(used_ + 4 > out_.size(), 0)) Grow();
  uint8_t* next = out_.data() + used_;
  do {
    *next++ = static_cast<uint8_t>(base >> 24);
    base <<= 8;
  } while ((length <<= 8) < arith_internal::kMinLength);
  used_ = static_cast<size_t>(next - out_.data());
  base_ = base;
  length_ = length;
}

inline void ArithmeticEncoder::EncodeBit(BitModel* m, uint32_t bit) {
  const uint32_t x = m->bit_0_prob_ * (length_ >> arith_internal::kBitLengthShift);
  if (bit == 0) {
    length_ = x;
    ++m->bit_0_count_;
  } else {
    const uint32_t init_base = base_;
    base_ += x;
    length_ -= x;
    if (init_base > base_) PropagateCarry();
  }
  if (length_ < arith_internal::kMinLength) Renormalize();
  if (__builtin_expect(--m->bits_until_update_ == 0, 0)) m->Update();
}

inline void ArithmeticEncoder::EncodeSymbol(SymbolModel* m, uint32_t sym) {
  if (__builtin_expect(m->distribution_.empty(), 0)) m->Start(false);
  const uint32_t init_base = base_;
  const uint32_t* dist = m->distribution_.data();
  if (sym == m->last_symbol_) {  // the interval's top: no product needed (as the decoder)
    const uint32_t x = dist[sym] * (length_ >> arith_internal::kSymbolLengthShift);
    base_ += x;
    length_ -= x;
  } else {
    const uint32_t x = dist[sym] * (length_ >>= arith_internal::kSymbolLengthShift);
    base_ += x;
    length_ = dist[sym + 1] * length_ - x;
  }
  if (init_base > base_) PropagateCarry();
  if (length_ < arith_internal::kMinLength) Renormalize();
  ++m->symbol_count_[sym];
  if (__builtin_expect(--m->symbols_until_update_ == 0, 0)) m->Update(false);
}

inline void ArithmeticEncoder::WriteRaw(uint32_t bits, uint32_t value) {
  const uint32_t init_base = base_;
  base_ += value * (length_ >>= bits);
  if (init_base > base_) PropagateCarry();
  if (length_ < arith_internal::kMinLength) Renormalize();
}

inline void ArithmeticEncoder::WriteBits(uint32_t bits, uint32_t value) {
  if (bits > 19) {  // as the decoder's ReadBits: the low 16 bits first
    WriteShort(static_cast<uint16_t>(value & 0xFFFF));
    value >>= 16;
    bits -= 16;
  }
  WriteRaw(bits, value);
}

inline void ArithmeticEncoder::WriteInt(uint32_t value) {
  WriteShort(static_cast<uint16_t>(value & 0xFFFF));
  WriteShort(static_cast<uint16_t>(value >> 16));
}

inline void ArithmeticEncoder::WriteInt64(uint64_t value) {
  WriteInt(static_cast<uint32_t>(value));
  WriteInt(static_cast<uint32_t>(value >> 32));
}

inline void IntegerCoder::WriteCorrector(ArithmeticEncoder* encoder, int32_t corrector,
                                         SymbolModel* model) {
  // k: the class of the tightest interval [-(2^k - 1), 2^k] holding c (c = 2^k counts as k).
  const uint32_t c = static_cast<uint32_t>(corrector);
  uint32_t c1 = corrector <= 0 ? 0u - c : c - 1;
  k_ = c1 == 0 ? 0 : 32 - static_cast<uint32_t>(__builtin_clz(c1));
  encoder->EncodeSymbol(model, k_);
  if (k_ == 0) {  // c is 0 or 1
    encoder->EncodeBit(&m_corrector0_, c);
    return;
  }
  if (k_ >= 32) return;  // only corr_min_ (INT32_MIN) has class 32
  // The inverse of ReadCorrector's mapping into [0, 2^k).
  const uint32_t mapped = corrector < 0 ? c + ((1u << k_) - 1) : c - 1;
  if (k_ <= bits_high_) {
    encoder->EncodeSymbol(&m_corrector_[k_ - 1], mapped);
  } else {  // the high bits_high bits modelled, the low k - bits_high raw
    const uint32_t low_bits = k_ - bits_high_;
    encoder->EncodeSymbol(&m_corrector_[k_ - 1], mapped >> low_bits);
    encoder->WriteBits(low_bits, mapped & ((1u << low_bits) - 1));
  }
}

inline void IntegerCoder::Compress(ArithmeticEncoder* encoder, int32_t prediction, int32_t real,
                                   uint32_t context) {
  // The corrector folded into [corr_min_, corr_max_], in unsigned arithmetic as Decompress.
  int32_t corr =
      static_cast<int32_t>(static_cast<uint32_t>(real) - static_cast<uint32_t>(prediction));
  if (corr < corr_min_) {
    corr = static_cast<int32_t>(static_cast<uint32_t>(corr) + corr_range_);
  } else if (corr > corr_max_) {
    corr = static_cast<int32_t>(static_cast<uint32_t>(corr) - corr_range_);
  }
  WriteCorrector(encoder, corr, &m_bits_[context]);
}

inline int32_t IntegerCoder::ReadCorrector(ArithmeticDecoder* decoder, SymbolModel* model) {
  k_ = decoder->DecodeSymbol(model);
  if (k_ == 0) return static_cast<int32_t>(decoder->DecodeBit(&m_corrector0_));  // 0 or 1
  if (k_ >= 32) return corr_min_;
  uint32_t c = decoder->DecodeSymbol(&m_corrector_[k_ - 1]);
  if (k_ > bits_high_) {  // the high bits were modelled, the low k - bits_high are raw
    const uint32_t low_bits = k_ - bits_high_;
    c = (c << low_bits) | decoder->ReadBits(low_bits);
  }
  // c in [0, 2^k): [0, 2^(k-1)) maps to [-(2^k - 1), -2^(k-1)], the rest to [2^(k-1) + 1, 2^k].
  if (c >= (1u << (k_ - 1))) {
    c += 1;
  } else {
    c -= (1u << k_) - 1;
  }
  return static_cast<int32_t>(c);
}

inline int32_t IntegerCoder::Decompress(ArithmeticDecoder* decoder, int32_t prediction,
                                               uint32_t context) {
  // Unsigned arithmetic: LASzip's int32 sums wrap, which is undefined for signed C++ integers.
  uint32_t real = static_cast<uint32_t>(prediction) +
                  static_cast<uint32_t>(ReadCorrector(decoder, &m_bits_[context]));
  if (static_cast<int32_t>(real) < 0) {
    real += corr_range_;
  } else if (real >= corr_range_) {
    real -= corr_range_;
  }
  return static_cast<int32_t>(real);
}

// Median of the last five values (LASzip StreamingMedian5): an insertion into a sorted window
// that alternately drops the lowest and the highest value. Both compressors predict with it, and
// its exact update order matters: the decoder must predict what the encoder predicted.
class Median5 {
 public:
  int32_t Get() const { return v_[2]; }
  void Add(int32_t v) {
    if (high_) {
      AddHigh(v);
    } else {
      AddLow(v);
    }
  }

 private:
  void AddHigh(int32_t v) {
    if (v < v_[2]) {
      v_[4] = v_[3], v_[3] = v_[2];
      if (v < v_[0]) {
        v_[2] = v_[1], v_[1] = v_[0], v_[0] = v;
      } else if (v < v_[1]) {
        v_[2] = v_[1], v_[1] = v;
      } else {
        v_[2] = v;
      }
    } else {
      if (v < v_[3]) {
        v_[4] = v_[3], v_[3] = v;
      } else {
        v_[4] = v;
      }
      high_ = false;
    }
  }
  void AddLow(int32_t v) {
    if (v_[2] < v) {
      v_[0] = v_[1], v_[1] = v_[2];
      if (v_[4] < v) {
        v_[2] = v_[3], v_[3] = v_[4], v_[4] = v;
      } else if (v_[3] < v) {
        v_[2] = v_[3], v_[3] = v;
      } else {
        v_[2] = v;
      }
    } else {
      if (v_[1] < v) {
        v_[0] = v_[1], v_[1] = v;
      } else {
        v_[0] = v;
      }
      high_ = true;
    }
  }
  std::array<int32_t, 5> v_{};
  bool high_ = true;
};

}  // namespace candi::io::laz
