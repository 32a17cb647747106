// What every task's episodes share, free of the simulated world so that the agent's code can
// use it too: the published number of next-best poses per episode (a task may allow more,
// Task::episode_length) and the reward of a successful step.
#pragma once

namespace qte::tasks {

constexpr int kPublishedEpisodeLength = 10;
constexpr float kSuccessReward = 100.0f;

}  // namespace qte::tasks
