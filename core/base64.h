// Base64 (RFC 4648, standard alphabet, '=' padding) of bytes, for binary data inside text
// messages (a PNG in the viewer's JSON reply). Thread-safe.
#pragma once

#include <string>

namespace candi {

std::string Base64(const std::string& bytes);

}  // namespace candi
