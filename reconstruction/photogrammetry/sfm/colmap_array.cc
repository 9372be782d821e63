// COLMAP 3.8 dense arrays (depth and normal maps; declared in colmap_model.h): the byte layout
// of src/mvs/mat.h (Mat::ReadBinary / WriteBinary): "W&H&C&" in ASCII, then the floats.
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

#include <charconv>
#include <cmath>
#include <cstring>
#include <string>

#include "core/atomic_file.h"
#include "core/check.h"

namespace candi::photogrammetry {

ColmapArray ReadColmapArray(const std::string& path) {
  const std::string data = ReadFileToString(path);
  ColmapArray array;
  size_t pos = 0;
  int* fields[3] = {&array.width, &array.height, &array.channels};
  for (int f = 0; f < 3; ++f) {
    const size_t amp = data.find('&', pos);
    if (amp == std::string::npos || amp - pos > 10 || amp == pos) {
      throw InputError(path, "byte " + std::to_string(pos),
                       "bad header: expected \"WIDTH&HEIGHT&CHANNELS&\" (COLMAP depth/normal map)");
    }
    const auto result = std::from_chars(data.data() + pos, data.data() + amp, *fields[f]);
    if (result.ec != std::errc() || result.ptr != data.data() + amp || *fields[f] <= 0) {
      throw InputError(path, "byte " + std::to_string(pos),
                       "bad header field '" + data.substr(pos, amp - pos) + "' (must be an integer > 0)");
    }
    pos = amp + 1;
  }
  const uint64_t left = data.size() - pos;
  // In 128 bits: three int32 fields can wrap 64 bits to a small count that the bytes match.
  const unsigned __int128 wide = static_cast<unsigned __int128>(array.width) *
                                 static_cast<unsigned __int128>(array.height) *
                                 static_cast<unsigned __int128>(array.channels);
  if (wide * 4 != left) {
    throw InputError(path, "byte " + std::to_string(pos),
                     "header " + std::to_string(array.width) + "x" + std::to_string(array.height) +
                         "x" + std::to_string(array.channels) + " needs " +
                         (wide >> 64 ? std::string("more than 2^64")
                                     : std::to_string(static_cast<uint64_t>(wide))) +
                         " floats but " + std::to_string(left) + " bytes follow");
  }
  const uint64_t count = static_cast<uint64_t>(wide);
  array.data.resize(count);
  std::memcpy(array.data.data(), data.data() + pos, count * 4);
  for (uint64_t i = 0; i < count; ++i) {
    if (!std::isfinite(array.data[i])) {
      throw InputError(path, "byte " + std::to_string(pos + 4 * i), "non-finite value");
    }
  }
  return array;
}

void WriteColmapArray(const ColmapArray& array, const std::string& path) {
  CANDI_CHECK(array.width > 0 && array.height > 0 && array.channels > 0)
      << array.width << "x" << array.height << "x" << array.channels;
  CANDI_CHECK_EQ(array.data.size(), static_cast<size_t>(array.width) * array.height * array.channels);
  AtomicFile file(path);
  file.Write(std::to_string(array.width) + "&" + std::to_string(array.height) + "&" +
             std::to_string(array.channels) + "&");
  file.Write(array.data.data(), array.data.size() * sizeof(float));
  file.Commit();
}

}  // namespace candi::photogrammetry
