// libFuzzer target: 'action' records (qte-select's next-best poses) through the planner's goal
// reader, and whole agent episodes (obs, action, trajectory) through keyframe --agent's
// converter, which reads the actions' per-depth indices and bounds. Run: make fuzz.
#include "fuzz_support.hpp"
#include "keyframes/transitions.hpp"
#include "planning/motion_planner.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  qte::keyframes::TransitionOptions options;
  options.demo = false;
  qte::keyframes::AgentEpisodeConverter converter(options);
  const qte::stream::Emit drop = [](const qte::stream::Record&) {};
  qte::fuzz::for_each_record(data, size, [&](const qte::stream::Record& record) {
    if (record.type() == "action") (void)qte::planning::goal_from(record);
    converter.handle(record, drop);
  });
  try {
    converter.finish(drop);
  } catch (const qte::Error&) {
  }
  return 0;
}
