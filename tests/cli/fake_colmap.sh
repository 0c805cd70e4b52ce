#!/bin/sh
# A stand-in for COLMAP in the tests of `mipnerf-cl dataset from-photos --colmap tests/cli/fake_colmap.sh`: feature
# extraction, matching and database cleaning do nothing; the mapper writes the 3-view text model of tests/data/fixtures/colmap/sparse,
# with only its first 2 views into an output folder named mapper_attempt_1 (a run that left a photo out) and with all
# 3 into any other. What it checks: the tool maps again while photos stay unregistered and keeps the best run.
step=$1
shift
case "$step" in
  feature_extractor | exhaustive_matcher | sequential_matcher | database_cleaner) exit 0 ;;
  mapper) ;;
  *) echo "fake_colmap.sh: unknown step '$step'" >&2; exit 2 ;;
esac
out=""
while [ $# -gt 0 ]; do
  if [ "$1" = "--output_path" ]; then out=$2; fi
  shift
done
[ -n "$out" ] || { echo "fake_colmap.sh: mapper without --output_path" >&2; exit 2; }
model="$(cd "$(dirname "$0")/../data/fixtures/colmap/sparse" && pwd)"
mkdir -p "$out/0"
cp "$model/cameras.txt" "$out/0/"
case "$out" in
  *mapper_attempt_1)
    # Views 1 and 2 (two lines each after the 3 comment lines); the points' tracks without view 3 (the pair "3 k").
    head -n 7 "$model/images.txt" > "$out/0/images.txt"
    sed 's/ 3 [0-9]*$//' "$model/points3D.txt" > "$out/0/points3D.txt"
    echo "Registering image #2 (2)" ;;
  *)
    cp "$model/images.txt" "$model/points3D.txt" "$out/0/"
    echo "Registering image #3 (3)" ;;
esac
