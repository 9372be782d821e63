#include "io/image/png_io.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "core/atomic_file.h"

namespace candi::io {

namespace {

// The encoded bytes, and why appending to them failed (out of memory), if it did.
struct PngSink {
  std::string bytes;
  std::string error;
};

void AppendCallback(png_structp png, png_bytep data, png_size_t length) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    sink->bytes.append(reinterpret_cast<const char*>(data), length);
  } catch (const std::exception& e) {
    sink->error = e.what();
    ok = false;
  }
  // png_error longjmps: call it outside the handler so the exception object is destroyed first.
  if (!ok) png_error(png, "write failed");
}
void FlushCallback(png_structp) {}

void ErrorCallback(png_structp png, png_const_charp message) {
  auto* text = static_cast<std::string*>(png_get_error_ptr(png));
  if (text != nullptr && text->empty()) *text = message;
  png_longjmp(png, 1);
}
void WarningCallback(png_structp, png_const_charp) {}

int ColorType(int channels) {
  switch (channels) {
    case 1: return PNG_COLOR_TYPE_GRAY;
    case 3: return PNG_COLOR_TYPE_RGB;
    default: return PNG_COLOR_TYPE_RGBA;
  }
}

// The libpng calls, under setjmp. No local is modified after setjmp, so none can be clobbered.
bool WriteWithLibpng(png_structp png, png_infop info, int width, int height, int bits,
                     int color_type, PngCompression compression, std::vector<png_text>& chunks,
                     png_bytepp rows, PngSink* sink) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_write_fn(png, sink, AppendCallback, FlushCallback);
  png_set_IHDR(png, info, width, height, bits, color_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (compression == PngCompression::kFast) {
    png_set_compression_level(png, 1);
    png_set_filter(png, 0, PNG_FILTER_SUB);  // no per-row search among the five filters
  } else {
    png_set_compression_level(png, 3);
  }
  if (!chunks.empty()) png_set_text(png, info, chunks.data(), static_cast<int>(chunks.size()));
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

struct PngReadResult {
  int width = 0, height = 0, channels = 0, depth = 0;
  std::vector<uint8_t> buffer;
  std::vector<png_bytep> rows;  // here, not a local: a longjmp would skip its destructor
  PngText text;
};

bool ReadWithLibpng(png_structp png, png_infop info, FILE* fp, PngReadResult* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, fp);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  png_set_palette_to_rgb(png);
  png_set_expand_gray_1_2_4_to_8(png);
  png_set_tRNS_to_alpha(png);
  // Grey stays one channel; grey + alpha (two channels) becomes RGBA.
  if (png_get_color_type(png, info) == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  out->width = png_get_image_width(png, info);
  out->height = png_get_image_height(png, info);
  out->channels = png_get_channels(png, info);
  out->depth = png_get_bit_depth(png, info);
  const size_t row_bytes = png_get_rowbytes(png, info);
  out->buffer.resize(row_bytes * out->height);
  out->rows.resize(out->height);
  for (int y = 0; y < out->height; ++y) out->rows[y] = out->buffer.data() + y * row_bytes;
  png_read_image(png, out->rows.data());
  png_textp texts = nullptr;
  int num_text = 0;
  png_get_text(png, info, &texts, &num_text);
  for (int i = 0; i < num_text; ++i) out->text[texts[i].key] = texts[i].text;
  return true;
}

template <typename T>
std::string EncodePngImpl(const Image<T>& image, const PngText& text, PngCompression compression) {
  CANDI_CHECK(!image.empty()) << "EncodePng: empty image";
  constexpr int kBits = sizeof(T) * 8;
  PngSink sink;
  std::string error;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, ErrorCallback,
                                            WarningCallback);
  CANDI_CHECK(png != nullptr);
  png_infop info = png_create_info_struct(png);
  // Rows are prepared before setjmp so no C++ object with a destructor lives across longjmp.
  const size_t row_values = static_cast<size_t>(image.width()) * image.channels();
  std::vector<png_bytep> rows(image.height());
  std::vector<uint8_t> big_endian;
  if (kBits == 16) {
    big_endian.resize(image.values().size() * 2);
    for (size_t i = 0; i < image.values().size(); ++i) {
      const uint16_t v = static_cast<uint16_t>(image.values()[i]);
      big_endian[2 * i] = static_cast<uint8_t>(v >> 8);
      big_endian[2 * i + 1] = static_cast<uint8_t>(v & 0xff);
    }
  }
  for (int y = 0; y < image.height(); ++y) {
    rows[y] = kBits == 16 ? big_endian.data() + y * row_values * 2
                          : reinterpret_cast<png_bytep>(const_cast<T*>(image.data())) + y * row_values;
  }
  std::vector<png_text> chunks;
  for (const auto& [key, value] : text) {
    png_text t;
    std::memset(&t, 0, sizeof(t));
    t.compression = PNG_TEXT_COMPRESSION_NONE;
    t.key = const_cast<char*>(key.c_str());
    t.text = const_cast<char*>(value.c_str());
    t.text_length = value.size();
    chunks.push_back(t);
  }
  const bool ok = WriteWithLibpng(png, info, image.width(), image.height(), kBits,
                                  ColorType(image.channels()), compression, chunks, rows.data(),
                                  &sink);
  png_destroy_write_struct(&png, &info);
  if (!ok) throw InputError("PNG encoding failed: " + (sink.error.empty() ? error : sink.error));
  return std::move(sink.bytes);
}

template <typename T>
void WritePngImpl(const std::string& path, const Image<T>& image, const PngText& text) {
  CANDI_CHECK(!image.empty()) << "WritePng: empty image for " << path;
  WriteFileAtomic(path, EncodePngImpl(image, text, PngCompression::kBalanced));
}

}  // namespace

std::string EncodePng(const Image8& image, const PngText& text, PngCompression compression) {
  return EncodePngImpl(image, text, compression);
}
std::string EncodePng(const Image16& image, const PngText& text, PngCompression compression) {
  return EncodePngImpl(image, text, compression);
}

void WritePng(const std::string& path, const Image8& image, const PngText& text) {
  WritePngImpl(path, image, text);
}
void WritePng(const std::string& path, const Image16& image, const PngText& text) {
  WritePngImpl(path, image, text);
}

PngImage ReadPng(const std::string& path) {
  FILE* fp = std::fopen(path.c_str(), "rb");
  if (fp == nullptr) throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  std::unique_ptr<FILE, int (*)(FILE*)> guard(fp, std::fclose);
  unsigned char sig[8];
  if (std::fread(sig, 1, 8, fp) != 8 || png_sig_cmp(sig, 0, 8) != 0) {
    throw InputError(path, "byte 0", "not a PNG file (bad signature)");
  }
  std::string error;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, ErrorCallback,
                                           WarningCallback);
  png_infop info = png_create_info_struct(png);
  PngImage result;
  PngReadResult raw;
  const bool ok = ReadWithLibpng(png, info, fp, &raw);
  png_destroy_read_struct(&png, &info, nullptr);
  if (!ok) throw InputError(path, "", "PNG read failed: " + error);
  if (raw.channels == 2) throw InputError(path, "", "grey+alpha PNG could not be expanded");
  const std::vector<uint8_t>& buffer = raw.buffer;
  result.text = std::move(raw.text);
  result.bit_depth = raw.depth;
  if (raw.depth == 16) {
    result.image16 = Image16(raw.width, raw.height, raw.channels);
    for (size_t i = 0; i < result.image16.values().size(); ++i) {
      result.image16.values()[i] = static_cast<uint16_t>(buffer[2 * i] << 8 | buffer[2 * i + 1]);
    }
  } else {
    result.image8 = Image8(raw.width, raw.height, raw.channels);
    std::memcpy(result.image8.data(), buffer.data(), buffer.size());
  }
  return result;
}

}  // namespace candi::io
