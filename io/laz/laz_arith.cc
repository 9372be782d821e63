#include "io/laz/laz_arith.h"

#include <algorithm>
#include <cstdint>

#include "core/check.h"

namespace candi::io::laz {

namespace {
constexpr uint32_t kBitMaxCount = 1u << arith_internal::kBitLengthShift;
constexpr uint32_t kSymbolMaxCount = 1u << arith_internal::kSymbolLengthShift;
}  // namespace

// ---- BitModel ----

BitModel::BitModel() { Reset(); }

void BitModel::Reset() {
  // Equiprobable, with frequent updates at first.
  bit_0_count_ = 1;
  bit_count_ = 2;
  bit_0_prob_ = 1u << (arith_internal::kBitLengthShift - 1);
  update_cycle_ = bits_until_update_ = 4;
}

void BitModel::Update() {
  if ((bit_count_ += update_cycle_) > kBitMaxCount) {  // halve the counts at the threshold
    bit_count_ = (bit_count_ + 1) >> 1;
    bit_0_count_ = (bit_0_count_ + 1) >> 1;
    if (bit_0_count_ == bit_count_) ++bit_count_;
  }
  const uint32_t scale = 0x80000000u / bit_count_;
  bit_0_prob_ = (bit_0_count_ * scale) >> (31 - arith_internal::kBitLengthShift);
  update_cycle_ = (5 * update_cycle_) >> 2;
  if (update_cycle_ > 64) update_cycle_ = 64;
  bits_until_update_ = update_cycle_;
}

// ---- SymbolModel ----

SymbolModel::SymbolModel(uint32_t symbols) : symbols_(symbols) {
  CANDI_CHECK(symbols >= 2 && symbols <= 2048) << "SymbolModel needs 2..2048 symbols, got "
                                               << symbols;
  last_symbol_ = symbols - 1;
  if (symbols > 16) {  // larger alphabets decode through a table of distribution brackets
    uint32_t table_bits = 3;
    while (symbols > (1u << (table_bits + 2))) ++table_bits;
    table_size_ = 1u << table_bits;
    table_shift_ = arith_internal::kSymbolLengthShift - table_bits;
  } else {
    table_size_ = table_shift_ = 0;
  }
}

void SymbolModel::Start(bool with_table) {
  total_count_ = 0;
  update_cycle_ = symbols_;
  symbol_count_.assign(symbols_, 1u);
  distribution_.resize(symbols_);
  with_table = with_table && table_size_ != 0;
  if (with_table) decoder_table_.resize(table_size_ + 2);
  Update(with_table);
  symbols_until_update_ = update_cycle_ = (symbols_ + 6) >> 1;
}

void SymbolModel::Update(bool with_table) {
  if ((total_count_ += update_cycle_) > kSymbolMaxCount) {  // halve the counts at the threshold
    total_count_ = 0;
    for (uint32_t& c : symbol_count_) total_count_ += (c = (c + 1) >> 1);
  }
  // Cumulative distribution in 15 bits, and for large alphabets the table giving, for each
  // bracket of the top table_bits bits, the first symbol whose range reaches into it.
  const uint32_t scale = 0x80000000u / total_count_;
  uint32_t sum = 0;
  if (table_size_ == 0 || !with_table) {
    for (uint32_t k = 0; k < symbols_; ++k) {
      distribution_[k] = (scale * sum) >> (31 - arith_internal::kSymbolLengthShift);
      sum += symbol_count_[k];
    }
  } else {
    uint32_t s = 0;
    for (uint32_t k = 0; k < symbols_; ++k) {
      distribution_[k] = (scale * sum) >> (31 - arith_internal::kSymbolLengthShift);
      sum += symbol_count_[k];
      const uint32_t w = distribution_[k] >> table_shift_;
      while (s < w) decoder_table_[++s] = k - 1;
    }
    decoder_table_[0] = 0;
    while (s <= table_size_) decoder_table_[++s] = symbols_ - 1;
  }
  update_cycle_ = (5 * update_cycle_) >> 2;
  const uint32_t max_cycle = (symbols_ + 6) << 3;
  if (update_cycle_ > max_cycle) update_cycle_ = max_cycle;
  symbols_until_update_ = update_cycle_;
}

// ---- ArithmeticDecoder ----

void ArithmeticDecoder::Init(const uint8_t* begin, const uint8_t* end) {
  begin_ = next_ = begin;
  end_ = end;
  overrun_ = false;
  length_ = 0xFFFFFFFFu;
  value_ = 0;
  for (int i = 0; i < 4; ++i) value_ = (value_ << 8) | NextByte();
}

// ---- ArithmeticEncoder ----

void ArithmeticEncoder::Init() {
  used_ = 0;
  base_ = 0;
  length_ = 0xFFFFFFFFu;
}

void ArithmeticEncoder::Grow() { out_.resize(std::max<size_t>(4096, 2 * out_.size())); }

void ArithmeticEncoder::Done() {
  // Pick a value inside the final interval that takes one byte (or two when the interval is
  // short), then pad with zeros: the decoder reads 4 bytes ahead of what it decodes.
  const uint32_t init_base = base_;
  bool another_byte = true;
  if (length_ > 2 * arith_internal::kMinLength) {
    base_ += arith_internal::kMinLength;
    length_ = arith_internal::kMinLength >> 1;
  } else {
    base_ += arith_internal::kMinLength >> 1;
    length_ = arith_internal::kMinLength >> 9;
    another_byte = false;
  }
  if (init_base > base_) PropagateCarry();
  Renormalize();
  for (int i = 0; i < (another_byte ? 3 : 2); ++i) {
    if (used_ == out_.size()) Grow();
    out_[used_++] = 0;
  }
}

// ---- IntegerCoder ----

IntegerCoder::IntegerCoder(uint32_t bits, uint32_t contexts, uint32_t bits_high,
                                         uint32_t range)
    : bits_(bits), contexts_(contexts), bits_high_(bits_high), range_(range) {
  CANDI_CHECK(bits >= 1 && bits <= 32) << "IntegerCoder bits = " << bits;
  CANDI_CHECK(contexts >= 1) << "IntegerCoder needs a context";
  if (range != 0) {  // the corrector's significant bits and range
    corr_bits_ = 0;
    corr_range_ = range;
    for (uint32_t r = range; r != 0; r >>= 1) ++corr_bits_;
    if (corr_range_ == (1u << (corr_bits_ - 1))) --corr_bits_;
    corr_min_ = -static_cast<int32_t>(corr_range_ / 2);
    corr_max_ = static_cast<int32_t>(static_cast<uint32_t>(corr_min_) + corr_range_ - 1);
  } else if (bits < 32) {
    corr_bits_ = bits;
    corr_range_ = 1u << bits;
    corr_min_ = -static_cast<int32_t>(corr_range_ / 2);
    corr_max_ = static_cast<int32_t>(static_cast<uint32_t>(corr_min_) + corr_range_ - 1);
  } else {
    corr_bits_ = 32;
    corr_range_ = 0;
    corr_min_ = INT32_MIN;
    corr_max_ = INT32_MAX;
  }
}

void IntegerCoder::Init() {
  k_ = 0;
  if (m_bits_.empty()) {
    m_bits_.assign(contexts_, SymbolModel(corr_bits_ + 1));
    m_corrector_.reserve(corr_bits_);
    for (uint32_t i = 1; i <= corr_bits_; ++i) {
      m_corrector_.emplace_back(i <= bits_high_ ? 1u << i : 1u << bits_high_);
    }
  } else {
    for (SymbolModel& m : m_bits_) m.Reset();
    for (SymbolModel& m : m_corrector_) m.Reset();
  }
  m_corrector0_.Reset();
}

}  // namespace candi::io::laz
