// libFuzzer target: 'frame' and 'transition' records (keyframe's output) through the learner's
// checks, the replay buffer and the minibatch assembly (voxelization of a sampled transition's
// frames). Run: make fuzz.
#include <random>

#include "fuzz_support.hpp"
#include "learner/minibatch.hpp"
#include "replay/replay_buffer.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qte::learner::LearnerConfig config;
  config.batch = 2;
  qte::replay::ReplayBuffer replay;
  qte::fuzz::for_each_record(data, size, [&](const qte::stream::Record& record) {
    if (record.type() == "transition") qte::learner::check_transition(record, config);
    replay.add(record);
  });
  if (replay.size() == 0) return 0;
  std::mt19937_64 rng(1);
  try {
    (void)qte::learner::assemble_minibatch(replay, replay.sample(2, 1.0, rng), config);
  } catch (const qte::Error&) {
  }
  return 0;
}
