// The viewer's WebSocket messages (view/protocol.h ParseClientMessage): whatever a page (or
// anyone who has the token) sends. A message either parses into a checked view or pick, or throws
// std::invalid_argument; a parsed view must make a valid camera.
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "view/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const candi::view::ClientMessage m = candi::view::ParseClientMessage(text);
    if (m.type == candi::view::MessageType::kView) {
      m.view.camera.Check();  // throws (uncaught: a finding) if the parser let a bad camera through
      m.view.camera.MakeProjector();
      if (m.view.settings.spbr.EffectiveRepeatLevel() < 1 ||
          m.view.camera.width > candi::view::kMaxImageSide)
        std::abort();
    }
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
