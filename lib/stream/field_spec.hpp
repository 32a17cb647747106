// Fields written on a command line (stream-pack), e.g.
//   task=reach_target            text
//   seed:i64=7                   scalar
//   pose:f64[7]=0,0,1,1,0,0,0    array with shape (values in C order)
//   rgb=@front_rgb.npy           array from a NumPy file
#pragma once

#include <string>

#include "stream/record.hpp"

namespace qte::stream {

// Parses one spec and adds the field to `record`; throws Error naming the spec.
void add_field_from_spec(Record& record, const std::string& spec);

}  // namespace qte::stream
