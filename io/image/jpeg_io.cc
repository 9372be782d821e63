#include "io/image/jpeg_io.h"

// jpeglib.h needs size_t and FILE declared before it.
#include <cstddef>
#include <cstdio>
#include <jpeglib.h>
#include <jerror.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/atomic_file.h"
#include "io/image/png_io.h"

namespace candi::io {

namespace {

// libjpeg reports errors through error_exit, which must not return: it longjmps back to the
// function that called libjpeg. Those functions hold no C++ object with a destructor across the
// jump (buffers are allocated outside them), so nothing leaks or is skipped.
struct ErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
  bool truncated;
};

void ErrorExit(j_common_ptr info) {
  auto* manager = reinterpret_cast<ErrorManager*>(info->err);
  (*info->err->format_message)(info, manager->message);
  std::longjmp(manager->jump, 1);
}
// Warnings stay quiet (cameras write harmless ones, e.g. extraneous bytes before a marker), except
// a premature end of file: libjpeg would fill the rest with grey, candi refuses the file.
void EmitMessage(j_common_ptr info, int level) {
  if (level < 0 && info->err->msg_code == JWRN_JPEG_EOF)
    reinterpret_cast<ErrorManager*>(info->err)->truncated = true;
}

jpeg_error_mgr* InstallErrorManager(ErrorManager* err) {
  jpeg_error_mgr* base = jpeg_std_error(&err->base);
  err->base.error_exit = ErrorExit;
  err->base.emit_message = EmitMessage;
  err->message[0] = '\0';
  err->truncated = false;
  return base;
}

// Largest image read: 2^28 pixels (16384 x 16384), ~805 MB as RGB. A header claiming more is
// refused before anything is allocated.
constexpr uint64_t kMaxPixels = uint64_t{1} << 28;

bool ReadHeader(jpeg_decompress_struct* cinfo, ErrorManager* err, const unsigned char* data,
                unsigned long size) {
  if (setjmp(err->jump)) return false;
  jpeg_create_decompress(cinfo);
  jpeg_mem_src(cinfo, data, size);
  jpeg_read_header(cinfo, TRUE);
  return true;
}

bool Decompress(jpeg_decompress_struct* cinfo, ErrorManager* err, unsigned char* out,
                size_t row_bytes) {
  if (setjmp(err->jump)) return false;
  jpeg_start_decompress(cinfo);
  while (cinfo->output_scanline < cinfo->output_height) {
    JSAMPROW row = out + static_cast<size_t>(cinfo->output_scanline) * row_bytes;
    jpeg_read_scanlines(cinfo, &row, 1);
  }
  jpeg_finish_decompress(cinfo);
  return true;
}

bool Compress(jpeg_compress_struct* cinfo, ErrorManager* err, const Image8* image, int channels,
              int quality, const unsigned char* rows_rgb, unsigned char** buffer,
              unsigned long* size) {
  if (setjmp(err->jump)) return false;
  jpeg_create_compress(cinfo);
  jpeg_mem_dest(cinfo, buffer, size);
  cinfo->image_width = static_cast<JDIMENSION>(image->width());
  cinfo->image_height = static_cast<JDIMENSION>(image->height());
  cinfo->input_components = channels;
  cinfo->in_color_space = channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(cinfo);
  jpeg_set_quality(cinfo, quality, TRUE);
  jpeg_start_compress(cinfo, TRUE);
  const size_t row_bytes = static_cast<size_t>(image->width()) * channels;
  while (cinfo->next_scanline < cinfo->image_height) {
    JSAMPROW row = const_cast<unsigned char*>(rows_rgb) + cinfo->next_scanline * row_bytes;
    jpeg_write_scanlines(cinfo, &row, 1);
  }
  jpeg_finish_compress(cinfo);
  return true;
}

bool IsJpeg(const std::string& bytes) {
  return bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
         static_cast<unsigned char>(bytes[1]) == 0xD8 && static_cast<unsigned char>(bytes[2]) == 0xFF;
}
bool IsPng(const std::string& bytes) { return bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0; }

Image8 DecodeJpeg(const std::string& path, const std::string& bytes) {
  if (!IsJpeg(bytes)) throw InputError(path, "byte 0", "not a JPEG file (bad signature)");
  jpeg_decompress_struct cinfo;
  ErrorManager err;
  cinfo.err = InstallErrorManager(&err);
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  if (!ReadHeader(&cinfo, &err, data, static_cast<unsigned long>(bytes.size()))) {
    jpeg_destroy_decompress(&cinfo);
    throw InputError(path, "", std::string("JPEG read failed: ") + err.message);
  }
  const J_COLOR_SPACE space = cinfo.jpeg_color_space;
  if (space == JCS_CMYK || space == JCS_YCCK) {
    jpeg_destroy_decompress(&cinfo);
    throw InputError(path, "", "CMYK JPEG is not supported (convert it to RGB)");
  }
  const int channels = space == JCS_GRAYSCALE ? 1 : 3;
  cinfo.out_color_space = channels == 1 ? JCS_GRAYSCALE : JCS_RGB;
  const uint64_t pixels = uint64_t{cinfo.image_width} * cinfo.image_height;
  if (pixels == 0 || pixels > kMaxPixels) {
    const std::string size = std::to_string(cinfo.image_width) + "x" + std::to_string(cinfo.image_height);
    jpeg_destroy_decompress(&cinfo);
    throw InputError(path, "header", "JPEG of " + size + " pixels is outside 1 .. 2^28 pixels");
  }
  Image8 image(static_cast<int>(cinfo.image_width), static_cast<int>(cinfo.image_height), channels);
  const bool ok = Decompress(&cinfo, &err, image.data(), static_cast<size_t>(image.width()) * channels);
  jpeg_destroy_decompress(&cinfo);
  if (!ok) throw InputError(path, "", std::string("JPEG read failed: ") + err.message);
  if (err.truncated) throw InputError(path, "", "JPEG read failed: the file ends early (truncated)");
  return image;
}

}  // namespace

Image8 ReadJpeg(const std::string& path) { return DecodeJpeg(path, ReadFileToString(path)); }

std::string EncodeJpeg(const Image8& image, int quality) {
  CANDI_CHECK(!image.empty()) << "EncodeJpeg: empty image";
  CANDI_CHECK(quality >= 1 && quality <= 100) << "EncodeJpeg: quality " << quality;
  const int channels = image.channels() == 1 ? 1 : 3;
  std::vector<unsigned char> packed;
  const unsigned char* rows = image.data();
  if (image.channels() == 4) {  // drop the alpha
    packed.resize(static_cast<size_t>(image.width()) * image.height() * 3);
    for (size_t i = 0, n = packed.size() / 3; i < n; ++i)
      std::memcpy(&packed[3 * i], image.data() + 4 * i, 3);
    rows = packed.data();
  }
  jpeg_compress_struct cinfo;
  ErrorManager err;
  cinfo.err = InstallErrorManager(&err);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  const bool ok = Compress(&cinfo, &err, &image, channels, quality, rows, &buffer, &size);
  jpeg_destroy_compress(&cinfo);
  std::string bytes;
  if (ok) bytes.assign(reinterpret_cast<const char*>(buffer), size);
  std::free(buffer);
  if (!ok) throw InputError(std::string("JPEG encoding failed: ") + err.message);
  return bytes;
}

namespace {

// TIFF's little-endian fields, appended.
void Put16(std::string* s, uint32_t v) {
  s->push_back(static_cast<char>(v & 0xff));
  s->push_back(static_cast<char>((v >> 8) & 0xff));
}
void Put32(std::string* s, uint32_t v) {
  Put16(s, v & 0xffff);
  Put16(s, v >> 16);
}
// A rational of 10^-4 steps (EXIF's RATIONAL: two unsigned 32-bit integers).
std::pair<uint32_t, uint32_t> Rational(double v) {
  return {static_cast<uint32_t>(std::llround(v * 10000.0)), 10000u};
}

// One IFD: entries of (tag, type, count, inline value or bytes stored after the IFD), written at
// `offset` (from the TIFF header), followed by the next-IFD link (0) and the out-of-line bytes.
struct IfdEntry {
  uint16_t tag, type;
  uint32_t count;
  std::string data;  // little-endian value bytes
};
std::string WriteIfd(std::vector<IfdEntry> entries, uint32_t offset) {
  std::sort(entries.begin(), entries.end(), [](const IfdEntry& a, const IfdEntry& b) { return a.tag < b.tag; });
  std::string ifd, extra;
  const uint32_t extra_at = offset + 2 + 12 * static_cast<uint32_t>(entries.size()) + 4;
  Put16(&ifd, static_cast<uint32_t>(entries.size()));
  for (const IfdEntry& e : entries) {
    Put16(&ifd, e.tag);
    Put16(&ifd, e.type);
    Put32(&ifd, e.count);
    if (e.data.size() <= 4) {
      std::string value = e.data;
      value.resize(4, '\0');
      ifd += value;
    } else {
      Put32(&ifd, extra_at + static_cast<uint32_t>(extra.size()));
      extra += e.data;
      if (extra.size() % 2) extra.push_back('\0');  // word alignment
    }
  }
  Put32(&ifd, 0);
  return ifd + extra;
}
IfdEntry Ascii(uint16_t tag, const std::string& text) { return {tag, 2, static_cast<uint32_t>(text.size() + 1), text + '\0'}; }
IfdEntry Short(uint16_t tag, uint32_t v) {
  std::string d;
  Put16(&d, v);
  return {tag, 3, 1, d};
}
IfdEntry Long(uint16_t tag, uint32_t v) {
  std::string d;
  Put32(&d, v);
  return {tag, 4, 1, d};
}
IfdEntry Rat(uint16_t tag, double v) {
  const auto [num, den] = Rational(v);
  std::string d;
  Put32(&d, num);
  Put32(&d, den);
  return {tag, 5, 1, d};
}

}  // namespace

double ExifFocalPixels(const JpegExif& exif, int width) { return exif.focal_mm / exif.sensor_width_mm * width; }

std::string EncodeJpegWithExif(const Image8& image, const JpegExif& exif, int quality) {
  if (!(exif.focal_mm > 0) || !(exif.sensor_width_mm > 0)) {
    throw std::invalid_argument("EXIF: focal_mm and sensor_width_mm must be > 0");
  }
  const std::string jpeg = EncodeJpeg(image, quality);
  // The TIFF structure: header, IFD0 (make, model, the Exif IFD's offset), the Exif IFD.
  const double pixels_per_cm = image.width() / (exif.sensor_width_mm / 10.0);
  std::vector<IfdEntry> exif_entries = {
      Rat(0x920A, exif.focal_mm),        Long(0xA002, static_cast<uint32_t>(image.width())),
      Long(0xA003, static_cast<uint32_t>(image.height())), Rat(0xA20E, pixels_per_cm),
      Rat(0xA20F, pixels_per_cm),        Short(0xA210, 3)};
  std::vector<IfdEntry> ifd0 = {Ascii(0x010F, exif.make), Ascii(0x0110, exif.model), Long(0x8769, 0)};
  const std::string ifd0_bytes = WriteIfd(ifd0, 8);
  ifd0.back() = Long(0x8769, 8 + static_cast<uint32_t>(ifd0_bytes.size()));
  std::string tiff = "II";
  Put16(&tiff, 42);
  Put32(&tiff, 8);
  tiff += WriteIfd(ifd0, 8);
  tiff += WriteIfd(exif_entries, static_cast<uint32_t>(tiff.size()));
  const std::string payload = std::string("Exif\0\0", 6) + tiff;
  std::string segment = "\xFF\xE1";
  Put16(&segment, 0);  // the length, big-endian, set below
  segment[2] = static_cast<char>(((payload.size() + 2) >> 8) & 0xff);
  segment[3] = static_cast<char>((payload.size() + 2) & 0xff);
  segment += payload;
  // After SOI and, when present, the JFIF APP0 segment libjpeg writes.
  size_t at = 2;
  if (jpeg.size() > 6 && static_cast<uint8_t>(jpeg[2]) == 0xFF && static_cast<uint8_t>(jpeg[3]) == 0xE0) {
    at = 4 + ((static_cast<uint8_t>(jpeg[4]) << 8) | static_cast<uint8_t>(jpeg[5]));
  }
  return jpeg.substr(0, at) + segment + jpeg.substr(at);
}

void WriteJpeg(const std::string& path, const Image8& image, int quality) {
  CANDI_CHECK(!image.empty()) << "WriteJpeg: empty image for " << path;
  WriteFileAtomic(path, EncodeJpeg(image, quality));
}

Image8 ReadImageRgb8(const std::string& path) {
  std::string bytes = ReadFileToString(path);
  Image8 image;
  if (IsJpeg(bytes)) {
    image = DecodeJpeg(path, bytes);
  } else if (IsPng(bytes)) {
    bytes = std::string();  // ReadPng reads the file itself
    PngImage png = ReadPng(path);
    if (png.bit_depth == 16) {
      const Image16& wide = png.image16;
      image = Image8(wide.width(), wide.height(), wide.channels());
      for (size_t i = 0; i < wide.values().size(); ++i)
        image.values()[i] = static_cast<uint8_t>((wide.values()[i] * 255u + 32767u) / 65535u);
    } else {
      image = std::move(png.image8);
    }
  } else {
    const bool tiff = bytes.compare(0, 4, "II*\0", 4) == 0 || bytes.compare(0, 4, "MM\0*", 4) == 0;
    throw InputError(path, "byte 0", std::string("not a PNG or JPEG file") +
                                         (tiff ? " (TIFF: convert it to PNG or JPEG)" : ""));
  }
  if (image.channels() == 3) return image;
  Image8 rgb(image.width(), image.height(), 3);
  const int c = image.channels();
  for (size_t i = 0, n = static_cast<size_t>(image.width()) * image.height(); i < n; ++i)
    for (int k = 0; k < 3; ++k) rgb.values()[3 * i + k] = image.values()[c * i + (c == 1 ? 0 : k)];
  return rgb;
}

}  // namespace candi::io
