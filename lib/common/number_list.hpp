// Comma-separated numbers ("0.1,0,0.8"), the one parser for them: options (cli::parse_reals),
// scene bounds and crop offsets (voxels).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

namespace qte {

// The numbers of `text`, or false with the first item that is not a whole finite number (an
// empty item, from ",," or a trailing comma, included) in `bad_item`.
inline bool parse_number_list(const std::string& text, std::vector<double>& numbers, std::string& bad_item) {
  numbers.clear();
  for (std::size_t at = 0; at <= text.size();) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    const std::string item = text.substr(at, comma - at);
    char* end = nullptr;
    const double value = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(value)) {
      bad_item = item;
      return false;
    }
    numbers.push_back(value);
    at = comma + 1;
  }
  return true;
}

}  // namespace qte
