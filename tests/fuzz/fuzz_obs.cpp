// libFuzzer target: 'obs' records (sim-step's observations) through every reader of them: the
// voxelizer's point cloud, the planner's start state, the networks' proprioception and
// keyframe's frame record. Run: make fuzz.
#include "fuzz_support.hpp"
#include "keyframes/transitions.hpp"
#include "planning/motion_planner.hpp"
#include "qattention/proprio.hpp"
#include "voxels/observation_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qte::fuzz::for_each_record(data, size, [](const qte::stream::Record& obs) {
    if (obs.type() != "obs") return;
    (void)qte::voxels::observation_cloud(obs);
    (void)qte::planning::start_state_from(obs);
    (void)qte::qattention::proprio_of(obs, 0);
    (void)qte::keyframes::frame_record(obs, 1);
  });
  return 0;
}
