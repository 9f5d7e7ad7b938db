#!/bin/bash
# The simulated training set of config/models/field-grey.onnx: frames and
# label images of every crop preset (seeds 101-103, outside every seed an
# evaluation uses), gathered into OUT/images and OUT/labels with unique
# names, for `plantscale train-segmenter` (docs/learned-segmentation.md).
#   tools/sim_training_set.sh OUT [PLANTSCALE]
set -euo pipefail
out=${1:?usage: tools/sim_training_set.sh OUT [PLANTSCALE]}
plantscale=${2:-build/app/plantscale}
mkdir -p "$out/images" "$out/labels"
for preset in field A B C D testbed lettuce-fast cabbage-wide treatment long; do
  for seed in 101 102 103; do
    pass="$out/passes/$preset-$seed"
    rm -rf "$pass"
    "$plantscale" simulate --preset "$preset" --seed "$seed" --length-m 10 --out "$pass" --every 60 --quiet
    for f in "$pass"/frames/*.png; do
      n=$(basename "$f")
      cp "$f" "$out/images/$preset-$seed-$n"
      cp "$pass/labels/$n" "$out/labels/$preset-$seed-$n"
    done
  done
done
echo "$(ls "$out/images" | wc -l) frames in $out/images"
