// COLMAP's lens models on normalised coordinates, and their inverse by Newton's method.
#include "core/lens.hpp"

#include <cmath>

#include "core/error.hpp"

namespace mipnerf {

Uv distort(const Lens& lens, const Uv& uv) {
  const double u = uv[0], v = uv[1];
  const double r2 = u * u + v * v;
  switch (lens.model) {
    case LensModel::pinhole:
      return uv;
    case LensModel::simple_radial:
      return {u * (1 + lens.k1 * r2), v * (1 + lens.k1 * r2)};
    case LensModel::radial: {
      const double radial = 1 + lens.k1 * r2 + lens.k2 * r2 * r2;
      return {u * radial, v * radial};
    }
    case LensModel::opencv: {
      const double radial = 1 + lens.k1 * r2 + lens.k2 * r2 * r2;
      return {u * radial + 2 * lens.p1 * u * v + lens.p2 * (r2 + 2 * u * u),
              v * radial + lens.p1 * (r2 + 2 * v * v) + 2 * lens.p2 * u * v};
    }
    case LensModel::full_opencv: {
      const double r4 = r2 * r2, r6 = r4 * r2;
      const double radial = (1 + lens.k1 * r2 + lens.k2 * r4 + lens.k3 * r6) / (1 + lens.k4 * r2 + lens.k5 * r4 + lens.k6 * r6);
      return {u * radial + 2 * lens.p1 * u * v + lens.p2 * (r2 + 2 * u * u),
              v * radial + lens.p1 * (r2 + 2 * v * v) + 2 * lens.p2 * u * v};
    }
    case LensModel::opencv_fisheye: {
      const double r = std::sqrt(r2);
      if (r < 1e-15) return uv;  // θ_d/r → 1 at the centre
      const double theta = std::atan(r), t2 = theta * theta;
      const double theta_d = theta * (1 + t2 * (lens.k1 + t2 * (lens.k2 + t2 * (lens.k3 + t2 * lens.k4))));
      return {u * theta_d / r, v * theta_d / r};
    }
  }
  return uv;
}

namespace {
double jacobian_determinant(const Lens& lens, const Uv& uv) {
  const double h = 1e-7;
  const Uv fu_plus = distort(lens, {uv[0] + h, uv[1]}), fu_minus = distort(lens, {uv[0] - h, uv[1]});
  const Uv fv_plus = distort(lens, {uv[0], uv[1] + h}), fv_minus = distort(lens, {uv[0], uv[1] - h});
  return ((fu_plus[0] - fu_minus[0]) * (fv_plus[1] - fv_minus[1]) - (fv_plus[0] - fv_minus[0]) * (fu_plus[1] - fu_minus[1])) /
         (4 * h * h);
}
// Whether the lens is one-to-one on the segment from the image centre to `uv`: the Jacobian's determinant stays
// positive along it. A root beyond a fold (where the radial profile turns back) is another ray for the same pixel,
// mirrored (determinant < 0) or, beyond a second fold, turned half a revolution (determinant > 0 again, so the
// determinant at the root alone does not tell); the lens's own ray is the one reached from the centre without a fold.
bool on_first_sheet(const Lens& lens, const Uv& uv) {
  const int samples = 32;
  for (int i = 1; i <= samples; ++i) {
    const double s = double(i) / samples;
    if (!(jacobian_determinant(lens, {s * uv[0], s * uv[1]}) > 0)) return false;
  }
  return true;
}
}  // namespace

bool undistort(const Lens& lens, const Uv& distorted_in, Uv& uv) {
  const Uv distorted = distorted_in;  // a copy: callers may pass the same array as `uv`
  uv = distorted;
  if (lens.is_pinhole()) return true;
  const double h = 1e-7;  // central-difference step of the Jacobian, in normalised units
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Uv f = distort(lens, uv);
    const double ru = f[0] - distorted[0], rv = f[1] - distorted[1];
    const Uv fu_plus = distort(lens, {uv[0] + h, uv[1]}), fu_minus = distort(lens, {uv[0] - h, uv[1]});
    const Uv fv_plus = distort(lens, {uv[0], uv[1] + h}), fv_minus = distort(lens, {uv[0], uv[1] - h});
    const double a = (fu_plus[0] - fu_minus[0]) / (2 * h), b = (fv_plus[0] - fv_minus[0]) / (2 * h);
    const double c = (fu_plus[1] - fu_minus[1]) / (2 * h), d = (fv_plus[1] - fv_minus[1]) / (2 * h);
    const double det = a * d - b * c;
    if (!std::isfinite(det) || std::abs(det) < 1e-12) return false;  // the lens folds here: not invertible
    const double du = (d * ru - b * rv) / det, dv = (a * rv - c * ru) / det;
    uv = {uv[0] - du, uv[1] - dv};
    if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) return false;
    if (std::abs(du) < 1e-14 && std::abs(dv) < 1e-14) break;
  }
  const Uv back = distort(lens, uv);
  if (std::abs(back[0] - distorted[0]) > 1e-12 || std::abs(back[1] - distorted[1]) > 1e-12) return false;
  return on_first_sheet(lens, uv);
}

void check_lens(const Lens& lens, const std::string& where) {
  for (double k : {lens.k1, lens.k2, lens.k3, lens.k4, lens.k5, lens.k6, lens.p1, lens.p2}) {
    if (!std::isfinite(k)) throw Error(where + ": a " + lens_model_name(lens.model) + " coefficient is not finite");
  }
}

}  // namespace mipnerf
