// libFuzzer target: 'checkpoint' records (qattn-train's networks, qte-select's input): the
// settings are checked before anything is built, then, for settings small enough to build
// quickly (base channels <= 4, voxels <= 8), the networks are made and the weights loaded
// with every name, dtype and shape checked. Run: make fuzz.
#include "fuzz_support.hpp"
#include "nets/checkpoint.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qte::fuzz::for_each_record(data, size, [](const qte::stream::Record& record) {
    const qte::nets::CheckpointConfig config = qte::nets::checkpoint_config(record);
    if (config.net.base_channels > 4 || config.net.voxels > 8 || config.depths > 3) return;
    auto nets = qte::nets::make_coarse_to_fine_nets(config.net, config.depths);
    (void)qte::nets::load_checkpoint_record(record, nets, nullptr);
  });
  return 0;
}
