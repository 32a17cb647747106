// The qte-select stage: every record passes through; after each 'obs' that is not terminal, the
// action the networks choose for it (tree expansion, then exploration), as an 'action' record.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "qattention/acting.hpp"
#include "stream/field_names.hpp"
#include "stream/stage.hpp"
#include "voxels/observation_cloud.hpp"

namespace qte::qattention {

struct SelectOptions {
  voxels::CoarseToFine hierarchy;
  Branching branching;
  Exploration exploration;
  bool ignore_collisions = false;  // set in every action (plan-path then moves in a straight line)
  bool reload = false;             // take up a newer checkpoint at the first step of each episode
  std::string png_dir;             // pictures of the Q-values along each action's path
  uint64_t seed = 0;               // action n draws its exploration from derive_seed(seed, n)
  // What is made of each observation before acting on it (point-cloud filters); none: as it is.
  std::function<stream::Record(const stream::Record&)> prepare;
};

class SelectStage : public stream::Stage {
 public:
  SelectStage(CheckpointNetworks& networks, SelectOptions options);
  void handle(const stream::Record& record, const stream::Emit& emit) override;
  std::vector<std::string> reads() const override { return {record_type::obs}; }
  uint64_t actions() const { return actions_; }

 private:
  Action act_on(const stream::Record& obs, const voxels::ObservationCloud& observed, int32_t step);
  CheckpointNetworks& networks_;
  SelectOptions options_;
  DepthEvaluator evaluate_;
  uint64_t actions_ = 0;
};

}  // namespace qte::qattention
