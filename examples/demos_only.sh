#!/usr/bin/env bash
# Can the networks tell a task's lookalikes apart at all? Trained on the demonstrations alone (a
# run's, as learn.sh records them for SEED: no exploration, no RL budget) for far more learner
# steps than a run takes, then greedy on the 50 held-out scenes acting with K = 1 and K = 10;
# failure_reasons.sh says where each episode went. If even then the share of tries at an object
# that go for the right one stays at chance, the finest depth has not learned what tells the
# objects apart, and no tree expansion can use it.
# Usage: demos_only.sh TASK OUT_DIR   (the built programs on PATH; settings from the
#        environment: SEED 0, DEMOS 10, IMAGE 256x256, STEPS 2000, N_STEP 3, VARIATION 0, CHAIN_STEPS reset
#        (keyframe --chain-steps), KS "1 10" (the K the networks act with), DEMO_MARGIN 0
#        (qattn-train --demo-margin), DEMO_CROSS_ENTROPY 0 (qattn-train --demo-cross-entropy),
#        HEAD_INPUT pooled (qattn-train --head-input), CROP_AUGMENTATION on (off: keyframe
#        --no-crop-augmentation),
#        NET_OPTIONS e.g. "--depths 3 --offset 0.15,0.05", PLAN_OPTIONS as learn.sh's; make -C
#        examples demos-only, which sets PLAN_OPTIONS as the task's runs have it).
# Writes OUT_DIR/failures-stepSTEPS-kK.csv; resumable (the learner resumes, finished CSVs stay).
set -euo pipefail
task=$1 out=$2
: "${SEED:=0}" "${DEMOS:=10}" "${IMAGE:=256x256}" "${STEPS:=2000}" "${N_STEP:=3}" "${VARIATION:=0}" "${NET_OPTIONS:=}"
: "${CHAIN_STEPS:=reset}" "${KS:=1 10}" "${DEMO_MARGIN:=0}" "${DEMO_CROSS_ENTROPY:=0}" "${HEAD_INPUT:=pooled}"
: "${CROP_AUGMENTATION:=on}"
here=$(cd "$(dirname "$0")" && pwd)
source "$here/common.sh"
crop_option=$(crop_augmentation_option "$CROP_AUGMENTATION")
mkdir -p "$out"
if [ ! -f "$out/replay.rec" ]; then  # learn.sh's demonstrations for SEED, the same bytes
  demo-record --task "$task" --episodes "$DEMOS" --seed "$SEED" --scenes demo --variation "$VARIATION" --image-size "$IMAGE" \
    --compress --output "$out/demos.rec" 2> "$out/demos.log"
  keyframe --seed "$SEED" --chain-steps "$CHAIN_STEPS" $crop_option $NET_OPTIONS --output "$out/replay.rec.tmp" "$out/demos.rec" 2>> "$out/demos.log"
  mv "$out/replay.rec.tmp" "$out/replay.rec"
fi
qattn-train --resume --steps "$STEPS" --start-after 0 --checkpoint-every 250 --keep 20 --architecture light --batch 32 \
  --n-step "$N_STEP" --demo-margin "$DEMO_MARGIN" --demo-cross-entropy "$DEMO_CROSS_ENTROPY" --head-input "$HEAD_INPUT" $NET_OPTIONS --seed "$SEED" --threads 1 --checkpoint-dir "$out/ckpt" --metrics "$out/train.csv" \
  "$out/replay.rec" 2>> "$out/train.log"
for k in $KS; do
  csv=$out/failures-step$STEPS-k$k.csv
  [ -f "$csv" ] && continue
  VARIATION=$VARIATION bash "$here/failure_reasons.sh" "$task" "$(checkpoint_path "$out/ckpt" "$STEPS")" "$k" "$IMAGE" 50 \
    "demonstrations only, $STEPS steps${NET_OPTIONS:+ ($NET_OPTIONS)}, acting K=$k" "$SEED" > "$csv.tmp"
  mv "$csv.tmp" "$csv"
done
cat "$out"/failures-step"$STEPS"-k*.csv | awk 'NR == 1 || !/^label/'
