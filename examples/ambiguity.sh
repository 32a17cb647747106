#!/usr/bin/env bash
# Pictures and numbers of a task's coarse ambiguity (docs/tasks.md): the first front
# frame of one demonstration, what depth 0 sees, the depth-1 grids around the target and the
# distractors, and ambiguity.py's comparison of them.
# Usage: ambiguity.sh TASK [SEED] [IMAGE] [centres|places]   (with the built programs on
#        PATH; writes examples/images/TASK_depth0.png, TASK_depth1_target.png,
#        TASK_depth1_distractor.png). `places`: around where the expert puts things instead
#        (setup_checkers: the target square and its neighbours).
set -euo pipefail
task=$1 seed=${2:-1} image=${3:-256x256} around=${4:-centres}
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
demo-record --task "$task" --episodes 1 --seed "$seed" --image-size "$image" --objects --output "$tmp/demo.rec" 2>/dev/null
centres=$("$PYTHON" "$here/analysis/ambiguity.py" "$around" "$tmp/demo.rec")
args=(); for c in $centres; do args+=(--centre "$c"); done
stream-cat --type obs --head 1 "$tmp/demo.rec" | voxelize "${args[@]}" --png "$tmp/png" --output "$tmp/voxels.rec"
"$PYTHON" "$here/analysis/ambiguity.py" compare "$tmp/voxels.rec"
images=$here/images
cp "$tmp/png/000000.depth0.png" "$images/${task}_depth0.png"
cp "$tmp/png/000000.depth1.0.png" "$images/${task}_depth1_target.png"
cp "$tmp/png/000000.depth1.1.png" "$images/${task}_depth1_distractor.png"
