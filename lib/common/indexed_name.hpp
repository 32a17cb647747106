// The name of a file made for record (or action) `index`: the index zero-padded to 6 digits, a
// dot and the suffix ("000042.front.rgb.png"), so a directory lists in record order. Every
// program that writes a file per record (stream-png, stream-dump, voxelize, qte-select,
// xarm-export) and stream-png --attention, which finds qte-select's, name them with this.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace qte {

inline std::string indexed_name(uint64_t index, const std::string& suffix) {
  char digits[24];
  std::snprintf(digits, sizeof digits, "%06llu", static_cast<unsigned long long>(index));
  return std::string(digits) + "." + suffix;
}

}  // namespace qte
