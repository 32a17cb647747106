#include "qattention/select_stage.hpp"

#include <cmath>
#include <iostream>
#include <random>

#include "common/error.hpp"
#include "common/random.hpp"
#include "qattention/action_record.hpp"
#include "qattention/proprio.hpp"
#include "stream/field_names.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::qattention {

SelectStage::SelectStage(CheckpointNetworks& networks, SelectOptions options)
    : networks_(networks), options_(std::move(options)), evaluate_(network_evaluator(networks.nets())) {}

// One observation's action; an error of the networks (a diverged checkpoint) names the record.
Action SelectStage::act_on(const stream::Record& obs, const voxels::ObservationCloud& observed, int32_t step) {
  const std::vector<float> proprio = proprio_of(obs, step);
  for (float p : proprio)
    if (!std::isfinite(p)) obs.fail(fields::gripper_opening_m, "a finite gripper opening");
  std::mt19937_64 rng(derive_seed(options_.seed, actions_));
  try {
    return act(evaluate_, options_.hierarchy, observed.view(), proprio, options_.branching, options_.exploration, rng);
  } catch (const StreamError&) {
    throw;
  } catch (const Error& e) {
    throw StreamError(obs.position, std::string(e.what()) + " (checkpoint " + networks_.path() + ")");
  }
}

void SelectStage::handle(const stream::Record& record, const stream::Emit& emit) {
  emit(record);
  if (record.type() != record_type::obs) return;
  if (record.has(fields::terminal) && record.scalar<uint8_t>(fields::terminal) != 0) return;
  const int32_t step = record.scalar<int32_t>(fields::step);
  if (options_.reload && step == 0 && networks_.reload_if_changed())
    std::cerr << "qte-select: loaded checkpoint " << networks_.path() << " at training step " << networks_.step()
              << std::endl;
  // The action's pictures read `observed` later: it must outlive the action.
  const voxels::ObservationCloud observed =
      voxels::observation_cloud(options_.prepare ? options_.prepare(record) : record);
  voxels::require_points_in_scene(record, observed, options_.hierarchy.scene);  // never act on an empty scene
  Action action = act_on(record, observed, step);  // not const: its pictures compute their grids lazily
  if (!options_.png_dir.empty()) save_q_pictures(options_.png_dir, actions_, action);
  emit(action_record(action.choice, options_.ignore_collisions, options_.branching.k, action.explored,
                     networks_.step(), step));
  actions_ += 1;
}

}  // namespace qte::qattention
