// Network checkpoints as one `checkpoint` record (formats/record-stream.md): a float32 field
// per named tensor, `depth<d>.<parameter name>`, so Python loads weights by name; the config
// as scalar and str fields; optionally Adam's state, `adam.depth<d>.<parameter name>.exp_avg`,
// `.exp_avg_sq` (float32, the parameter's shape) and `.step` (int64).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nets/qattention_net.hpp"
#include "stream/record.hpp"

namespace torch::optim {
class Adam;
}

namespace qte::nets {

// What a checkpoint holds networks for: `depths` networks of `net`'s settings (its depth and
// is_last are those of depth 0).
struct CheckpointConfig {
  NetConfig net;
  int depths = 0;
  int64_t step = 0;
};

// The record of `nets` (one per depth, depth 0 first); `adam` may be null (weights only).
stream::Record checkpoint_record(const std::vector<QAttentionNet>& nets, const torch::optim::Adam* adam, int64_t step);
// Writes that one record to `path` atomically (the file appears complete or not at all).
void save_checkpoint(const std::string& path, const std::vector<QAttentionNet>& nets, const torch::optim::Adam* adam,
                     int64_t step);

CheckpointConfig checkpoint_config(const stream::Record& record);
CheckpointConfig read_checkpoint_config(const std::string& path);
// The online networks' 'checkpoint' record of the file at `path`, found by role (a 'checkpoint'
// record without a 'role' field; the target networks' has role "target"), after every record
// of the file has been read and checked, so damage anywhere in it is an error. Throws
// StreamError unless there is exactly one such record.
stream::Record read_online_checkpoint(const std::string& path);

// Loads weights into `nets` (and, when `adam` is given, its state for their parameters: none
// when the checkpoint has none) and returns the step. Everything is checked before anything
// is copied: the first difference in config, tensor names, dtypes or shapes throws Error
// naming the field; a damaged file throws StreamError.
int64_t load_checkpoint_record(const stream::Record& record, std::vector<QAttentionNet>& nets,
                               torch::optim::Adam* adam);
int64_t load_checkpoint(const std::string& path, std::vector<QAttentionNet>& nets, torch::optim::Adam* adam = nullptr);

}  // namespace qte::nets
