// PNG encoding, reading and writing (libpng), 8 or 16 bits, grey, RGB or RGBA.
//
// EncodePng gives a PNG's bytes in memory (the viewer's frames); WritePng encodes the same bytes
// and writes them atomically (temporary file, then rename). Text chunks carry provenance (seed,
// repeat level). Errors throw InputError, naming the path for files. Thread-safe (no shared state).
#pragma once

#include <map>
#include <string>

#include "core/image.h"

namespace candi::io {

using PngText = std::map<std::string, std::string>;  // tEXt key -> value (keys 1-79 Latin-1 chars)

// How hard zlib works. kBalanced: level 3 with libpng's adaptive filter choice, for files.
// kFast: level 1 with the Sub filter only, for frames that are sent once (candi view).
enum class PngCompression { kBalanced, kFast };

std::string EncodePng(const Image8& image, const PngText& text = {},
                      PngCompression compression = PngCompression::kBalanced);
std::string EncodePng(const Image16& image, const PngText& text = {},
                      PngCompression compression = PngCompression::kBalanced);

void WritePng(const std::string& path, const Image8& image, const PngText& text = {});
void WritePng(const std::string& path, const Image16& image, const PngText& text = {});

struct PngImage {
  Image8 image8;    // filled for 8-bit files (palette and low bit depths expanded to 8 bits)
  Image16 image16;  // filled for 16-bit files
  int bit_depth = 8;
  PngText text;
};
// Reads a PNG; palette images become RGB, grey+alpha becomes RGBA.
PngImage ReadPng(const std::string& path);

}  // namespace candi::io
