#!/bin/sh
# A stand-in for COLMAP in the tests of `mipnerf-cl dataset from-photos --colmap tests/cli/fake_colmap.sh`: feature
# extraction, matching and database cleaning do nothing; the mapper writes the 3-view text model of tests/data/fixtures/colmap/sparse,
# with only its first 2 views into an output folder named mapper_attempt_1 (a run that left a photo out) and with all
# 3 into any other. What it checks: the tool maps again while photos stay unregistered and keeps the best run.
# FAKE_COLMAP_SCENARIO changes the mapper:
#   forward-facing   without --Mapper.init_min_tri_angle it finds no initial pair, as COLMAP 3.8 says it (every
#                    relaxation tried, no model, exit 1); with it, all 3 views. Matching again fails the run: the
#                    tool must map the same matches again with the settings for small baselines.
#   no-initial-pair  it never finds an initial pair; matching again fails the run.
#   no-matches       it finds no matched images, as COLMAP says it.
#   two-models       two models, as COLMAP writes them when its first stops early: 0 with the first 2 views, then 1
#                    with all 3 (a later model may register photos an earlier one has too).
#   unseen-view      mapper_attempt_1 registers all 3 views, but the third sees none of the points (they are left
#                    out of its tracks), as COLMAP's small-baseline mapping once left a photo; later runs are whole.
# FAKE_COLMAP_EXPECT_PHOTOS: the photos feature extraction must be given (--image_list_path), space-separated.
step=$1
shift
case "$step" in
  exhaustive_matcher | sequential_matcher) exit 0 ;;
  feature_extractor)
    list=""
    while [ $# -gt 0 ]; do
      if [ "$1" = "--image_list_path" ]; then list=$2; fi
      shift
    done
    if [ -n "$FAKE_COLMAP_EXPECT_PHOTOS" ]; then
      given=$(tr '\n' ' ' < "$list" | sed 's/ $//')
      if [ "$given" != "$FAKE_COLMAP_EXPECT_PHOTOS" ]; then
        echo "fake_colmap.sh: features asked for '$given', expected '$FAKE_COLMAP_EXPECT_PHOTOS'" >&2
        exit 2
      fi
    fi
    exit 0 ;;
  database_cleaner)
    case "$FAKE_COLMAP_SCENARIO" in
      forward-facing | no-initial-pair)
        echo "fake_colmap.sh: matching again, though the mapper's trouble was the initial pair" >&2
        exit 2 ;;
    esac
    exit 0 ;;
  mapper) ;;
  *) echo "fake_colmap.sh: unknown step '$step'" >&2; exit 2 ;;
esac
out=""
small_baseline=""
while [ $# -gt 0 ]; do
  if [ "$1" = "--output_path" ]; then out=$2; fi
  if [ "$1" = "--Mapper.init_min_tri_angle" ]; then small_baseline=$2; fi
  shift
done
[ -n "$out" ] || { echo "fake_colmap.sh: mapper without --output_path" >&2; exit 2; }

no_initial_pair() {
  for _ in 1 2 3 4; do
    echo "Finding good initial image pair"
    echo "  => No good initial image pair found."
    echo "  => Relaxing the initialization constraints."
  done
  echo "Finding good initial image pair"
  echo "  => No good initial image pair found."
  echo "ERROR: failed to create sparse model" >&2
  exit 1
}
case "$FAKE_COLMAP_SCENARIO" in
  forward-facing) [ -n "$small_baseline" ] || no_initial_pair ;;
  no-initial-pair) no_initial_pair ;;
  no-matches)
    echo "WARNING: No images with matches found in the database."
    echo "ERROR: failed to create sparse model" >&2
    exit 1 ;;
esac

model="$(cd "$(dirname "$0")/../data/fixtures/colmap/sparse" && pwd)"
mkdir -p "$out/0"
cp "$model/cameras.txt" "$out/0/"
echo "Initializing with image pair #1 and #2"
if [ "$FAKE_COLMAP_SCENARIO" = "two-models" ]; then
  head -n 7 "$model/images.txt" > "$out/0/images.txt"
  sed 's/ 3 [0-9]*$//' "$model/points3D.txt" > "$out/0/points3D.txt"
  mkdir -p "$out/1"
  cp "$model/cameras.txt" "$model/images.txt" "$model/points3D.txt" "$out/1/"
  echo "Registering image #3 (3)"
  exit 0
fi
case "$FAKE_COLMAP_SCENARIO:$out" in
  unseen-view:*mapper_attempt_1)
    cp "$model/images.txt" "$out/0/"
    sed 's/ 3 [0-9]*$//' "$model/points3D.txt" > "$out/0/points3D.txt"
    echo "Registering image #3 (3)" ;;
  *:*mapper_attempt_1)
    # Views 1 and 2 (two lines each after the 3 comment lines); the points' tracks without view 3 (the pair "3 k").
    head -n 7 "$model/images.txt" > "$out/0/images.txt"
    sed 's/ 3 [0-9]*$//' "$model/points3D.txt" > "$out/0/points3D.txt"
    echo "Registering image #2 (2)" ;;
  *)
    cp "$model/images.txt" "$model/points3D.txt" "$out/0/"
    echo "Registering image #3 (3)" ;;
esac
