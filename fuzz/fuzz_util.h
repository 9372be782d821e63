// Shared helpers for the libFuzzer harnesses (fuzz/fuzz_<format>.cc): most candi readers take a
// path, so each input is written to a per-process scratch folder (in /dev/shm when it exists,
// else $TMPDIR or /tmp), reused from one input to the next and removed at exit.
// Multi-file formats (COLMAP models, the render archive) split one input into parts at the
// separator line kFuzzPartSeparator ("\n--candi-part--\n"), so mutations of one part leave the
// others in place (a length-prefixed container would shift every later part).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "io/point_file.h"

namespace candi::fuzz {

inline constexpr std::string_view kFuzzPartSeparator = "\n--candi-part--\n";

// The per-process scratch folder (created on first use), without a trailing '/'.
const std::string& ScratchDir();
// ScratchDir()/<name>, holding exactly `size` bytes of `data` (replacing what was there).
std::string WriteScratchFile(const std::string& name, const uint8_t* data, size_t size);
void WriteScratchFile(const std::string& path, std::string_view bytes);
// Removes ScratchDir()/<name> when present (a part the input does not provide).
void RemoveScratchFile(const std::string& name);
// A fresh empty folder ScratchDir()/<name> (its previous contents removed).
std::string FreshScratchFolder(const std::string& name);
// The input cut at kFuzzPartSeparator, at most max_parts parts (the last keeps any further
// separators).
std::vector<std::string_view> SplitParts(const uint8_t* data, size_t size, size_t max_parts);
// Opens a reader with `open(options)` and reads it to the end of the file, with the default options
// and then, when also_without_scalar_fields, with scalar_fields off. An InputError (the answer to
// bad input) ends a read; any other exception escapes to the fuzzer.
using ReaderOpener = std::function<std::unique_ptr<io::PointReader>(const io::PointReadOptions&)>;
void ReadToEnd(const ReaderOpener& open, bool also_without_scalar_fields = false);

}  // namespace candi::fuzz

// Every harness defines this (libFuzzer's entry point; fuzz/replay_main.cc calls it too).
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
