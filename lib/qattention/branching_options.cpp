#include "qattention/branching_options.hpp"

#include <cmath>

#include "common/error.hpp"

namespace qte::qattention {

std::vector<cli::OptionSpec> branching_options() {
  return {
      cli::real_option("k-margin", "M", "with K 'auto': expand every voxel whose Q is within M of the node's best", "",
                       0, 1e30),
      cli::real_option("k-mass", "P",
                       "with K 'auto': expand the fewest best voxels holding P (0 < P <= 1) of the node's softmax", "",
                       1e-9, 1),
      cli::integer_option("k-max", "N", "with K 'auto': expand at most N voxels per node", "10", 1, 4096),
  };
}

Branching parse_branching(const cli::Arguments& args, const std::string& k_option, int min_k) {
  const bool margin = args.has("k-margin"), mass = args.has("k-mass");
  if (args.text(k_option) != "auto") {
    if (margin || mass || args.has("k-max"))
      throw UsageError("--k-margin, --k-mass and --k-max go with --" + k_option + " auto");
    return Branching(static_cast<int>(args.integer(k_option, min_k, 4096)));
  }
  if (margin == mass) throw UsageError("--" + k_option + " auto needs one of --k-margin and --k-mass");
  const int k_max = static_cast<int>(args.integer("k-max"));
  if (margin) {
    const double m = args.real("k-margin");
    return Branching::within_margin(static_cast<float>(m), k_max);
  }
  const double p = args.real("k-mass");
  return Branching::softmax_mass(static_cast<float>(p), k_max);
}

std::string describe(const Branching& b) {
  if (!b.adaptive()) return std::to_string(b.k);
  char text[96];
  std::snprintf(text, sizeof text, "auto (%s %g, at most %d)", b.rule == Branching::Rule::margin ? "margin" : "mass",
                static_cast<double>(b.threshold), b.k);
  return text;
}

}  // namespace qte::qattention
