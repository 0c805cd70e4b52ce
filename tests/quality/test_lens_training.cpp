// Photos behind a lens train as they are, through the real executable: the procedural scene rendered through a
// known OPENCV lens and through an OPENCV_FISHEYE lens (its whole image: the corner pixel sees 55° from the axis where a
// pinhole of the same focal length sees 44°, so an undistort-first tool must crop it or stretch it), each trained for the
// same steps as its pinhole twin, scores within 0.5 dB of the twin on its own held-out views. What this cannot show
// on a scene this small: a lens-unaware run (the same photos with pinhole rays) scores about as well here, because
// the distortion moves mostly the background at the tiny model's resolution; the geometry of the lens rays is
// checked to 1e-4 px in tests/ops/test_rays_lens.cpp and tests/official/test_lenses.cpp.
#include <doctest/doctest.h>

#include <string>

#include "io/json.hpp"
#include "eval/render_fixtures.hpp"
#include "support/temp_scene.hpp"

using namespace mipnerf;

namespace {

// make-scene, train (tiny preset, 600 steps at lr 1e-3) and eval on the test split: the mean PSNR.
double trained_psnr(const std::string& name, const std::string& lens) {
  const std::string root = test::fresh_temp_dir("lens-twin-" + name).string();
  auto run = [](const std::string& args) {
    const test::CliResult result = test::run_cli(args);
    INFO(args << "\n" << result.err);
    REQUIRE(result.exit_code == 0);
  };
  run("make-scene " + root + "/scene --size 48 --views 40 --val-views 2 --test-views 8 --scales 1 --samples 4 --fov 70" +
      (lens.empty() ? "" : " --lens " + lens));
  run("train --data " + root + "/scene --out " + root + "/run --preset tiny --steps 600 --set lr_init=1e-3");
  run("eval --checkpoint " + root + "/run --split test --no-images --out " + root + "/eval");
  const double psnr = io::read_json(root + "/eval/metrics.json").at("mean").at("psnr").get<double>();
  MESSAGE(name << ": " << psnr << " dB on the test views after 600 steps");
  return psnr;
}

}  // namespace

TEST_CASE("lens training: OPENCV and fisheye photos train to within 0.5 dB of their pinhole twin at equal steps") {
  const double pinhole = trained_psnr("pinhole", "");
  CHECK(pinhole > 20.0);  // the twin itself learned the scene
  CHECK(trained_psnr("opencv", "OPENCV:-0.25,0.05,0.002,-0.002") > pinhole - 0.5);
  CHECK(trained_psnr("fisheye", "OPENCV_FISHEYE:0.02,-0.01,0.002,-0.0005") > pinhole - 0.5);
}
