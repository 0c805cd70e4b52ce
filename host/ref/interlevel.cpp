// CPU reference (double) of kernels/interlevel.cl.
#include "ref/interlevel.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

namespace mipnerf::ref {
namespace {

// P_k of the zero-padded step pdf, k = 0..N+1, with stepfun.weight_to_pdf's guards (float32's tiny and max, as the
// official's safe_div): a zero-width interval carries no density.
double interlevel_pdf_level(const double* c, const double* w, size_t k, size_t n_intervals) {
  if (k == 0 || k > n_intervals) return 0.0;
  const double width = c[k] - c[k - 1];
  return width < FLT_MIN ? 0.0 : std::min(w[k - 1] / width, static_cast<double>(FLT_MAX));
}

double interlevel_ramp_start(double c_k, double halfwidth) { return c_k - halfwidth; }

// blur_stepfun's max(plus_eps(c), c + r): plus_eps is the next float32 above c (FLT_MIN near 0).
double interlevel_ramp_end(double c_k, double halfwidth) {
  const double above =
      std::abs(c_k) < FLT_MIN
          ? static_cast<double>(FLT_MIN)
          : static_cast<double>(std::nextafter(static_cast<float>(c_k), std::numeric_limits<float>::infinity()));
  return std::max(c_k + halfwidth, above);
}

// p̃(x) with ramps trail..lead−1 under way; `absolute` sums |P_trail| + Σ (|P_{k+1}| + |P_k|) · ramp instead (the
// magnitudes: a jump's rounding is relative to the levels it is the difference of).
double interlevel_blurred_pdf(const double* c, const double* w, size_t n_intervals, double halfwidth, size_t trail,
                              size_t lead, double x, bool absolute) {
  double y = interlevel_pdf_level(c, w, trail, n_intervals);
  for (size_t k = trail; k < lead; ++k) {
    const double lo = interlevel_ramp_start(c[k], halfwidth), hi = interlevel_ramp_end(c[k], halfwidth);
    const double next = interlevel_pdf_level(c, w, k + 1, n_intervals),
                 here = interlevel_pdf_level(c, w, k, n_intervals);
    const double jump = absolute ? std::abs(next) + std::abs(here) : next - here;
    y += jump * std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
  }
  return std::max(y, 0.0);
}

// The kernel's walk over the lo knots, hi knots and queries in order; per query interval j, its area (of p̃, or of
// the magnitude when `absolute`) into area[j] and the knots met inside it into events[j] (when not null).
void interlevel_walk(const double* c, const double* w, size_t n_intervals, const double* cp, size_t n_proposal,
                     double halfwidth, bool absolute, double* area_out, double* events_out,
                     double* active_out = nullptr) {
  size_t lead = 0, trail = 0, query = 0;
  double x_prev = std::min(interlevel_ramp_start(c[0], halfwidth), cp[0]), y_prev = 0.0, area = 0.0, events = 0.0;
  double active = 0.0;  // the most ramps under way at once in this interval
  while (query <= n_proposal) {
    int event = 2;
    double x = cp[query];
    if (lead <= n_intervals && interlevel_ramp_start(c[lead], halfwidth) <= x) {
      event = 0;
      x = interlevel_ramp_start(c[lead], halfwidth);
    }
    if (trail < lead && interlevel_ramp_end(c[trail], halfwidth) < x) {
      event = 1;
      x = interlevel_ramp_end(c[trail], halfwidth);
    }
    const double y = interlevel_blurred_pdf(c, w, n_intervals, halfwidth, trail, lead, x, absolute);
    active = std::max(active, static_cast<double>(lead - trail));
    area += (x - x_prev) * 0.5 * (y_prev + y);
    x_prev = x;
    y_prev = y;
    if (event == 0) {
      ++lead;
      ++events;
    } else if (event == 1) {
      ++trail;
      ++events;
    } else {
      if (query > 0) {
        area_out[query - 1] = std::max(area, 0.0);
        if (events_out) events_out[query - 1] = events;
        if (active_out) active_out[query - 1] = active;
      }
      area = 0.0;
      events = 0.0;
      active = static_cast<double>(lead - trail);
      ++query;
    }
  }
}

}  // namespace

void blur_and_resample_weights(const double* c, const double* w, size_t n_intervals, const double* cp,
                               size_t n_proposal, double halfwidth, double* w_blur) {
  interlevel_walk(c, w, n_intervals, cp, n_proposal, halfwidth, false, w_blur, nullptr);
}

BlurMagnitudes blur_and_resample_magnitudes(const double* c, const double* w, size_t n_intervals, const double* cp,
                                            size_t n_proposal, double halfwidth) {
  BlurMagnitudes m;
  m.area_abs.assign(n_proposal, 0.0);
  m.events.assign(n_proposal, 0.0);
  m.ramp_jumps.assign(n_proposal, 0.0);
  m.active.assign(n_proposal, 0.0);
  interlevel_walk(c, w, n_intervals, cp, n_proposal, halfwidth, true, m.area_abs.data(), m.events.data(),
                  m.active.data());
  for (size_t k = 0; k <= n_intervals; ++k) {
    const double lo = interlevel_ramp_start(c[k], halfwidth), hi = interlevel_ramp_end(c[k], halfwidth);
    const double jump =
        std::abs(interlevel_pdf_level(c, w, k + 1, n_intervals)) + std::abs(interlevel_pdf_level(c, w, k, n_intervals));
    for (size_t j = 0; j < n_proposal; ++j) {
      // A float32 knot sits up to 2u (|c| + r) from its place: count that margin as part of the ramp.
      const double margin = 4 * 5.9604644775390625e-08 * (std::abs(c[k]) + halfwidth);
      const double overlap = std::min(hi + margin, cp[j + 1]) - std::max(lo - margin, cp[j]);
      if (overlap >= 0) m.ramp_jumps[j] += jump * overlap / (hi - lo);
    }
  }
  return m;
}

std::vector<double> blur_and_resample_float32_bound(const double* c, const double* w, size_t n_intervals,
                                                    const double* cp, size_t n_proposal, double halfwidth) {
  constexpr double u = 5.9604644775390625e-08;  // float32's unit roundoff, 2^-24
  const BlurMagnitudes mag = blur_and_resample_magnitudes(c, w, n_intervals, cp, n_proposal, halfwidth);
  double extent = 0;
  for (size_t k = 0; k <= n_intervals; ++k) extent = std::max(extent, std::abs(c[k]) + halfwidth);
  // A knot moved by δ = u (|c| + r) (and its ramp's width by 2δ) changes p̃ by at most |J| · 2δ / width over the ramp
  // and a margin past its ends: over interval j, |J| · 2δ · (its overlap with the ramp and margin) / width, which is
  // 2δ · ramp_jumps[j].
  std::vector<double> bound(n_proposal);
  for (size_t j = 0; j < n_proposal; ++j) {
    const double knots = 4 * u * extent * mag.ramp_jumps[j];
    bound[j] = (6.0 * (mag.active[j] + 2) + mag.events[j] + 8) * u * mag.area_abs[j] + knots;
  }
  return bound;
}

double interlevel_interval_loss(double w_blur, double wp) {
  const double excess = std::max(0.0, w_blur - wp);
  return excess * excess / (wp + kInterlevelEps);
}

void spline_interlevel_fwd(const double* c, const double* w, const double* cp, const double* wp, double halfwidth,
                           double* w_blur, double* ray_loss, size_t n_rays, size_t n_intervals, size_t n_proposal) {
  for (size_t ray = 0; ray < n_rays; ++ray) {
    double* ray_w_blur = w_blur + ray * n_proposal;
    blur_and_resample_weights(c + ray * (n_intervals + 1), w + ray * n_intervals, n_intervals,
                              cp + ray * (n_proposal + 1), n_proposal, halfwidth, ray_w_blur);
    double sum = 0.0;
    for (size_t j = 0; j < n_proposal; ++j) sum += interlevel_interval_loss(ray_w_blur[j], wp[ray * n_proposal + j]);
    ray_loss[ray] = sum;
  }
}

void spline_interlevel_bwd(const double* w_blur, const double* wp, double grad_scale, double* d_wp, size_t n_values) {
  for (size_t i = 0; i < n_values; ++i) {
    const double excess = std::max(0.0, w_blur[i] - wp[i]);
    const double ratio = excess / (wp[i] + kInterlevelEps);
    d_wp[i] = -grad_scale * ratio * (2.0 + ratio);
  }
}

double spline_interlevel_loss(const std::vector<double>& ray_loss, size_t n_proposal, double mult) {
  double sum = 0.0;
  for (double v : ray_loss) sum += v;
  return mult * sum / (static_cast<double>(ray_loss.size()) * static_cast<double>(n_proposal));
}

}  // namespace mipnerf::ref
