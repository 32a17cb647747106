// qte-select: the acting agent. Observations in, next-best poses chosen by coarse-to-fine
// Q-attention with tree expansion (C2F-ARM+QTE) out, with optional exploration.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <optional>
#include <random>

#include "cli/command.hpp"
#include "common/random.hpp"
#include "keyframes/keyframes.hpp"
#include "nets/checkpoint.hpp"
#include "qattention/proprio.hpp"
#include "qattention/tree_expansion.hpp"
#include "stream/reader.hpp"
#include "stream/writer.hpp"
#include "voxels/observation_cloud.hpp"
#include "voxels/voxel_image.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "qte-select";
  u.summary = "choose next-best poses with coarse-to-fine Q-attention and tree expansion (C2F-ARM+QTE)";
  u.description = {
      "The acting agent of the learning loop, a long-running filter. Every record passes through "
      "unchanged and in order; after each 'obs' record that is not terminal qte-select writes an "
      "'action' record: the next-best gripper pose for plan-path (pose, gripper_open, "
      "ignore_collisions) and what chose it: per depth the voxel, its grid's bounds, its centre "
      "and its Q-value; the rotation bins; the tree's value; the checkpoint's training step.",
      "The networks, one per depth, come from --checkpoint. The observation's point cloud (every "
      "camera's points, or points rebuilt from depth; pixels without a return are ignored) is "
      "voxelized at depth 0 over --bounds, and at each deeper depth over the cube of centre +- "
      "--offset around a voxel chosen above. Tree expansion keeps the --k best voxels of every "
      "non-leaf grid and expands each: all the grids of a depth are voxelized in one pass over "
      "the cloud and evaluated in one batched forward. A branch is worth (its voxel's Q + the "
      "value of the best branch below it) / 2, a last-depth grid its largest Q, and the agent "
      "acts on the best path (Algorithm 2 of the QTE paper); --k 1 is C2F-ARM's greedy choice. "
      "The pose is the centre of the last depth's voxel, turned by the last network's best "
      "rotation bins (Euler 'xyz', 72 bins of 5 degrees); the gripper command is the better of "
      "open and close.",
      "Exploration is off by default (evaluation). --epsilon E goes top-down and at each depth, "
      "with probability E, replaces the chosen voxel by a uniformly random voxel of that depth's "
      "grid and chooses the deeper depths below it again by tree expansion; --index-noise adds "
      "Gaussian noise (in voxels) to the last depth's index, --rotation-noise to the three "
      "rotation bins (wrapped around), and --gripper-flip flips the gripper command. An action "
      "that exploration changed has explored = 1; the Q-values and value it carries are those "
      "of the voxels taken. The random choices of the n-th action are drawn from --seed and n: "
      "same inputs and seed give the same bytes (unless --reload loads new weights).",
      "With --reload the checkpoint file is checked at the start of every episode (an "
      "observation with step 0) and loaded again when it changed (qattn-train replaces its "
      "DIR/latest.rec by an atomic rename while it learns), with a line on standard error; "
      "every action's checkpoint_step says which weights chose it.",
      "With --png DIR a picture of every depth's grid is saved for each action as "
      "DIR/<n>.depth<d>.png (n the action's index, from 000000): the occupied voxels coloured "
      "by Q (blue low, red high) and the chosen voxel outlined in red. It costs one more forward "
      "per depth.",
  };
  u.arguments = {{"FILE", "input records; '-' or absent is standard input", true, false}};
  u.options = {
      {"checkpoint", "FILE", "the networks: a 'checkpoint' record as qattn-train writes it (required)", ""},
      {"k", "K", "voxels expanded per non-leaf grid; 1 is C2F-ARM's greedy choice", "10"},
      {"voxels", "V", "voxels per side of every grid (default: the checkpoint's; must agree with it)", ""},
      {"depths", "D", "coarse-to-fine depths (default: the checkpoint's; must agree with it)", ""},
      {"bounds", "X,Y,Z,S", "scene bounds: minimum corner and edge length in metres", "-0.3,-0.5,0.6,1.0"},
      {"offset", "M", "half edge of the deeper grids, metres", "0.15"},
      {"epsilon", "E", "probability, per depth, of a random voxel instead of the chosen one", "0"},
      {"index-noise", "SIGMA", "standard deviation of Gaussian noise on the last depth's voxel index, voxels", "0"},
      {"rotation-noise", "BINS", "standard deviation of Gaussian noise on the rotation bins (5 degrees each)", "0"},
      {"gripper-flip", "P", "probability of flipping the gripper command", "0"},
      {"ignore-collisions", "", "set ignore_collisions in every action (straight-line moves)", ""},
      {"reload", "", "at the start of each episode, load the checkpoint again when the file changed", ""},
      {"threads", "N",
       "LibTorch threads; when a busy process (the learner) shares the cores, use 1 or set OMP_WAIT_POLICY=PASSIVE: "
       "OpenMP threads that spin while they wait make a forward about 50 times slower",
       "2"},
      {"png", "DIR", "save the Q-values of every depth's grid as DIR/<n>.depth<d>.png", ""},
      {"output", "FILE", "where to write; '-' is standard output", "-"},
  };
  u.uses_randomness = true;
  u.examples = {
      {"sim-step --task reach_target --episodes 10 < fifo | qte-select --checkpoint ckpt.rec | plan-path > fifo",
       "evaluate the networks on 10 episodes: the acting loop closed by a FIFO (mkfifo fifo)"},
      {"sim-step --task pick_and_lift --episodes 100 < fifo | qte-select --checkpoint run/latest.rec --reload "
       "--epsilon 0.1 --rotation-noise 2 | tee -a episodes.rec | plan-path > fifo",
       "an exploring actor that takes up the learner's newest weights at every episode and keeps "
       "what it saw and did"},
      {"sim-step --task lift_numbered_block < /dev/null | qte-select --checkpoint ckpt.rec --k 1 --png q/ "
       "| stream-dump --type action",
       "the greedy C2F-ARM choice for one observation, and pictures of its Q-values"},
  };
  u.see_also = {"qattn-train(1)", "plan-path(1)", "sim-step(1)", "voxelize(1)", "qte-stream(5)"};
  return u;
}

namespace {

// What identifies one version of a file on disk: a replacement renamed into place has another
// inode, and a rewrite another size or modification time.
struct FileVersion {
  dev_t device = 0;
  ino_t inode = 0;
  off_t size = 0;
  timespec modified{};
  bool operator==(const FileVersion& o) const {
    return device == o.device && inode == o.inode && size == o.size && modified.tv_sec == o.modified.tv_sec &&
           modified.tv_nsec == o.modified.tv_nsec;
  }
};

FileVersion file_version(const std::string& path) {
  struct stat s {};
  if (::stat(path.c_str(), &s) != 0) throw_system_error("cannot open " + path);
  return {s.st_dev, s.st_ino, s.st_size, s.st_mtim};
}

stream::Record checkpoint_record(const std::string& path) {
  stream::RecordReader reader(path);
  auto record = reader.next();
  if (!record) throw StreamError({path, 0, 0}, "expected a 'checkpoint' record, the file is empty");
  return std::move(*record);
}

// The networks of a checkpoint file, one per depth.
struct Networks {
  std::string path;
  FileVersion version;
  nets::CheckpointConfig config;
  std::vector<nets::QAttentionNet> nets;
  int64_t step = 0;

  explicit Networks(const std::string& checkpoint) : path(checkpoint) {
    version = file_version(path);
    const stream::Record record = checkpoint_record(path);
    config = nets::checkpoint_config(record);
    if (config.net.channels != voxels::kChannels)
      throw Error(path + ": the networks take " + std::to_string(config.net.channels) +
                  " channels per voxel; qte-select voxelizes " + std::to_string(voxels::kChannels));
    if (config.net.proprio != qattention::kProprio)
      throw Error(path + ": the networks take " + std::to_string(config.net.proprio) +
                  " proprioception inputs; qte-select gives " + std::to_string(qattention::kProprio));
    nets = nets::make_coarse_to_fine_nets(config.net, config.depths);
    step = nets::load_checkpoint_record(record, nets, nullptr);
  }

  // Loads the file again when it is not the version loaded; true when it did.
  bool reload_if_changed() {
    const FileVersion now = file_version(path);
    if (now == version) return false;
    step = nets::load_checkpoint_record(checkpoint_record(path), nets, nullptr);  // checks the configuration
    version = now;
    return true;
  }
};

struct Exploration {
  double epsilon = 0;         // per depth: a random voxel instead of the chosen one
  double index_noise = 0;     // voxels, on the last depth's index
  double rotation_noise = 0;  // bins
  double gripper_flip = 0;    // probability
};

int flat_index(const Eigen::Vector3i& i, int v) { return (i.x() * v + i.y()) * v + i.z(); }

constexpr int kOccupancyChannel = voxels::kChannels - 1;  // 1 when the voxel holds a point

// One grid along the chosen path, voxelized and evaluated alone (for pictures, and for the Q
// of a voxel that exploration put in place of the chosen one).
struct GridQ {
  std::vector<float> grid, q;
};

GridQ evaluate_grid(const std::vector<nets::QAttentionNet>& nets, int depth, const voxels::GridBounds& bounds,
                    const voxels::PointCloud& cloud, const std::vector<float>& proprio) {
  GridQ g;
  g.grid.resize(static_cast<std::size_t>(bounds.voxels) * bounds.voxels * bounds.voxels * voxels::kChannels);
  voxels::voxelize(cloud, bounds, g.grid.data());
  g.q = nets.at(depth).predict(g.grid.data(), proprio.data(), 1).translation;
  return g;
}

// The greedy (tree-expanded) choice changed by exploration. `replaced[d]` is set for the depths
// whose voxel was put in by exploration, so whose Q-value is still the old voxel's.
qattention::Choice explore(const qattention::Choice& chosen, const Exploration& e, std::mt19937_64& rng,
                           const std::vector<nets::QAttentionNet>& nets, const voxels::CoarseToFine& hierarchy,
                           const voxels::PointCloud& cloud, const std::vector<float>& proprio, int k,
                           std::vector<bool>& replaced) {
  qattention::Choice c = chosen;
  const int depths = hierarchy.depths, v = hierarchy.voxels();
  replaced.assign(depths, false);
  if (e.epsilon > 0) {
    std::bernoulli_distribution random_voxel(e.epsilon);
    std::uniform_int_distribution<int> any_index(0, v - 1);
    for (int d = 0; d < depths; ++d) {
      if (!random_voxel(rng)) continue;
      const int x = any_index(rng), y = any_index(rng), z = any_index(rng);
      c.indices[d] = Eigen::Vector3i(x, y, z);
      replaced[d] = true;
      if (d + 1 == depths) break;
      // The depths below, chosen again by tree expansion around the random voxel: a
      // hierarchy whose scene is the next depth's grid, evaluated by the deeper networks.
      const voxels::CoarseToFine below{hierarchy.bounds_at(d + 1, c.bounds[d].centre_of(c.indices[d])),
                                       depths - d - 1, hierarchy.offset_m};
      const qattention::DepthEvaluator deeper_nets = [&nets, d](int j, const float* grids, const float* p, int batch) {
        return nets.at(j + d + 1).predict(grids, p, batch);
      };
      const qattention::Choice deeper = qattention::expand(deeper_nets, below, cloud, proprio, k);
      for (int j = 0; j + d + 1 < depths; ++j) {
        c.indices[j + d + 1] = deeper.indices[j];
        c.bounds[j + d + 1] = deeper.bounds[j];
        c.q_values[j + d + 1] = deeper.q_values[j];
        replaced[j + d + 1] = false;
      }
      c.rotation_bins = deeper.rotation_bins;
      c.gripper_open = deeper.gripper_open;
      c.expanded_grids += deeper.expanded_grids;
    }
  }
  if (e.index_noise > 0) {
    std::normal_distribution<double> noise(0, e.index_noise);
    Eigen::Vector3i& last = c.indices.back();
    const Eigen::Vector3i before = last;
    for (int axis = 0; axis < 3; ++axis)
      last[axis] = static_cast<int>(std::clamp<long>(std::lround(last[axis] + noise(rng)), 0, v - 1));
    if (last != before) replaced.back() = true;
  }
  if (e.rotation_noise > 0) {
    std::normal_distribution<double> noise(0, e.rotation_noise);
    for (int axis = 0; axis < 3; ++axis) {
      const long bin = c.rotation_bins[axis] + std::lround(noise(rng));
      c.rotation_bins[axis] = static_cast<int>((bin % keyframes::kRotationBins + keyframes::kRotationBins) %
                                               keyframes::kRotationBins);
    }
  }
  if (e.gripper_flip > 0 && std::bernoulli_distribution(e.gripper_flip)(rng)) c.gripper_open = !c.gripper_open;
  return c;
}

bool same_action(const qattention::Choice& a, const qattention::Choice& b) {
  return a.indices == b.indices && a.rotation_bins == b.rotation_bins && a.gripper_open == b.gripper_open;
}

std::vector<double> bounds_field(const voxels::GridBounds& b) {
  return {b.min_corner.x(), b.min_corner.y(), b.min_corner.z(), b.size_m};
}

stream::Record action_record(const qattention::Choice& c, bool ignore_collisions, int k, bool explored,
                             int64_t checkpoint_step, int32_t step) {
  stream::Record a("action");
  const Eigen::Vector3d p = c.position();
  Eigen::Quaterniond q(keyframes::rotation_from_bins(c.rotation_bins));
  q.normalize();
  a.set<double>("pose", {7}, std::vector<double>{p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()});
  a.set_scalar<uint8_t>("gripper_open", c.gripper_open ? 1 : 0);
  a.set_scalar<uint8_t>("ignore_collisions", ignore_collisions ? 1 : 0);
  for (std::size_t d = 0; d < c.indices.size(); ++d) {
    const std::string prefix = "depth" + std::to_string(d);
    a.set<int32_t>(prefix + ".index", {3}, c.indices[d].data());
    a.set<double>(prefix + ".bounds", {4}, bounds_field(c.bounds[d]));
    const Eigen::Vector3d centre = c.bounds[d].centre_of(c.indices[d]);
    a.set<double>(prefix + ".centre", {3}, centre.data());
    a.set_scalar<float>(prefix + ".q_value", c.q_values[d]);
  }
  a.set<int32_t>("rotation_bins", {3}, c.rotation_bins.data());
  a.set_scalar<float>("value", c.value);
  a.set_scalar<int32_t>("k", k);
  a.set_scalar<uint8_t>("explored", explored ? 1 : 0);
  a.set_scalar<int64_t>("checkpoint_step", checkpoint_step);
  a.set_scalar<int32_t>("step", step);
  return a;
}

double probability(const cli::Arguments& args, const std::string& name) {
  const double x = args.real(name);
  if (!(x >= 0 && x <= 1)) throw UsageError("--" + name + " must be between 0 and 1");
  return x;
}

double non_negative(const cli::Arguments& args, const std::string& name) {
  const double x = args.real(name);
  if (!(x >= 0 && std::isfinite(x))) throw UsageError("--" + name + " must be a non-negative number");
  return x;
}

}  // namespace

static void run(const cli::Arguments& args) {
  const std::string checkpoint = args.text("checkpoint");
  if (checkpoint.empty()) throw UsageError("--checkpoint FILE is required");
  const int64_t k = args.integer("k");
  if (k < 1) throw UsageError("--k must be at least 1");
  const int64_t threads = args.integer("threads");
  if (threads < 1) throw UsageError("--threads must be at least 1");
  Exploration exploration;
  exploration.epsilon = probability(args, "epsilon");
  exploration.index_noise = non_negative(args, "index-noise");
  exploration.rotation_noise = non_negative(args, "rotation-noise");
  exploration.gripper_flip = probability(args, "gripper-flip");
  const double offset = args.real("offset");
  if (!(offset > 0)) throw UsageError("--offset must be positive");
  const bool ignore_collisions = args.flag("ignore-collisions"), reload = args.flag("reload");
  const std::string png_dir = args.text("png");

  nets::set_torch_threads(static_cast<int>(threads));
  Networks networks(checkpoint);
  const auto agree = [&](const char* option, int checkpoint_value) {
    if (args.has(option) && args.integer(option) != checkpoint_value)
      throw UsageError(std::string("--") + option + " " + args.text(option) + " differs from the checkpoint's " +
                       std::to_string(checkpoint_value) + " (" + checkpoint + ")");
  };
  agree("voxels", networks.config.net.voxels);
  agree("depths", networks.config.depths);
  voxels::CoarseToFine hierarchy;
  try {
    hierarchy.scene = voxels::GridBounds::parse(args.text("bounds"), networks.config.net.voxels);
  } catch (const Error& e) {
    throw UsageError(std::string("--bounds: ") + e.what());
  }
  hierarchy.depths = networks.config.depths;
  hierarchy.offset_m = offset;
  if (!png_dir.empty() && ::mkdir(png_dir.c_str(), 0755) != 0 && errno != EEXIST)
    throw_system_error("cannot create directory " + png_dir);

  const int v = hierarchy.voxels();
  stream::RecordReader reader(args.positional().empty() ? "-" : args.positional()[0]);
  stream::RecordWriter writer(args.text("output"));
  uint64_t actions = 0;
  while (auto record = reader.next()) {
    writer.write(*record);
    if (record->type() != "obs") continue;
    if (record->has("terminal") && record->scalar<uint8_t>("terminal") != 0) continue;
    const voxels::ObservationCloud observed = voxels::observation_cloud(*record);
    const voxels::PointCloud cloud = observed.view();
    const int32_t step = record->scalar<int32_t>("step");
    if (reload && step == 0 && networks.reload_if_changed())
      std::cerr << "qte-select: loaded checkpoint " << checkpoint << " at training step " << networks.step << std::endl;
    const std::vector<float> proprio = qattention::proprio_of(*record, step);

    const qattention::Choice chosen = qattention::expand(qattention::network_evaluator(networks.nets), hierarchy,
                                                         cloud, proprio, static_cast<int>(k));
    std::mt19937_64 rng(derive_seed(args.seed(), actions));
    std::vector<bool> replaced;
    qattention::Choice taken =
        explore(chosen, exploration, rng, networks.nets, hierarchy, cloud, proprio, static_cast<int>(k), replaced);
    const bool explored = !same_action(taken, chosen);
    if (!explored) taken = chosen;

    // Grids along the taken path evaluated alone, when needed.
    std::vector<std::optional<GridQ>> path(hierarchy.depths);
    const auto grid_q = [&](int d) -> const GridQ& {
      if (!path[d]) path[d] = evaluate_grid(networks.nets, d, taken.bounds[d], cloud, proprio);
      return *path[d];
    };
    if (explored) {
      for (int d = 0; d < hierarchy.depths; ++d)
        if (replaced[d]) taken.q_values[d] = grid_q(d).q[flat_index(taken.indices[d], v)];
      // The value of the path taken, as the tree values its best path: from the last depth up.
      float value = taken.q_values.back();
      for (int d = hierarchy.depths - 2; d >= 0; --d) value = (taken.q_values[d] + value) / 2;
      taken.value = value;
    }
    if (!png_dir.empty()) {
      char name[32];
      for (int d = 0; d < hierarchy.depths; ++d) {
        const GridQ& g = grid_q(d);
        const int chosen_voxel = flat_index(taken.indices[d], v);
        voxels::VoxelImageOptions picture;
        picture.min_value = std::numeric_limits<float>::lowest();
        picture.values.assign(g.q.size(), picture.min_value);  // empty voxels are not drawn
        for (std::size_t i = 0; i < g.q.size(); ++i)
          if (g.grid[i * voxels::kChannels + kOccupancyChannel] > 0 || static_cast<int>(i) == chosen_voxel)
            picture.values[i] = g.q[i];
        picture.marked_x = taken.indices[d].x();
        picture.marked_y = taken.indices[d].y();
        picture.marked_z = taken.indices[d].z();
        std::snprintf(name, sizeof name, "/%06llu.depth%d.png", static_cast<unsigned long long>(actions), d);
        voxels::save_voxel_png(png_dir + name, g.grid.data(), v, picture);
      }
    }
    writer.write(action_record(taken, ignore_collisions, static_cast<int>(k), explored, networks.step, step));
    actions += 1;
  }
  writer.close();
}

int main(int argc, char** argv) {
  nets::use_passive_openmp_waits(argv);
  return cli::run_tool(argc, argv, usage(), run);
}
