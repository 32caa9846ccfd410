// vff/version.h - the library's own version (not the file format's: see format.h).
#pragma once

namespace vff {
inline constexpr int kLibraryVersionMajor = 0;
inline constexpr int kLibraryVersionMinor = 1;
inline constexpr int kLibraryVersionPatch = 0;
inline constexpr const char* kLibraryVersion = "0.1.0";
}  // namespace vff
