// The tessellated icosahedron's directions (geodesic_basis.hpp): written from the construction the official
// geopoly.generate_basis describes, not copied.
#include "core/geodesic_basis.hpp"

#include <cmath>
#include <string>

#include "core/error.hpp"

namespace mipnerf {
namespace {

using Vec = std::array<double, 3>;

double squared_distance(const Vec& a, const Vec& b) {
  double sum = 0;
  for (int i = 0; i < 3; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return sum;
}

// Two tessellated vertices are the same point when closer than this (squared), as the official's eps = 1e-4: distinct
// vertices of a tessellation of v ≤ 64 lie much further apart.
constexpr double kSamePointSq = 1e-4;

// The 12 vertices of an icosahedron on the unit sphere and its 20 faces, in the official's order.
std::vector<Vec> icosahedron_vertices() {
  const double a = (std::sqrt(5.0) + 1.0) / 2.0, norm = std::sqrt(a + 2.0);
  const double raw[12][3] = {{-1, 0, a}, {1, 0, a}, {-1, 0, -a}, {1, 0, -a}, {0, a, 1},  {0, a, -1},
                             {0, -a, 1}, {0, -a, -1}, {a, 1, 0}, {-a, 1, 0}, {a, -1, 0}, {-a, -1, 0}};
  std::vector<Vec> vertices;
  for (const auto& v : raw) vertices.push_back({v[0] / norm, v[1] / norm, v[2] / norm});
  return vertices;
}

constexpr int kIcosahedronFaces[20][3] = {{0, 4, 1},  {0, 9, 4},  {9, 5, 4},  {4, 5, 8},  {4, 8, 1},
                                          {8, 10, 1}, {8, 3, 10}, {5, 3, 8},  {5, 2, 3},  {2, 7, 3},
                                          {7, 10, 3}, {7, 6, 10}, {7, 11, 6}, {11, 0, 6}, {0, 1, 6},
                                          {6, 1, 10}, {9, 0, 11}, {9, 11, 2}, {9, 2, 5},  {7, 2, 11}};

// Every face's tessellated points on the unit sphere, face after face, duplicates kept at their first place only.
std::vector<Vec> tessellated_sphere(int v) {
  const auto corners = icosahedron_vertices();
  std::vector<Vec> points;
  for (const auto& face : kIcosahedronFaces) {
    for (int i = 0; i <= v; ++i) {
      for (int j = 0; j <= v - i; ++j) {
        const double w[3] = {double(i) / v, double(j) / v, double(v - i - j) / v};
        Vec p{0, 0, 0};
        for (int c = 0; c < 3; ++c) {
          for (int k = 0; k < 3; ++k) p[k] += w[c] * corners[static_cast<size_t>(face[c])][k];
        }
        const double length = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        for (double& x : p) x /= length;
        bool seen = false;
        for (const auto& q : points) seen = seen || squared_distance(p, q) <= kSamePointSq;
        if (!seen) points.push_back(p);
      }
    }
  }
  return points;
}

}  // namespace

std::vector<std::array<double, 3>> icosahedron_basis(int tessellation) {
  if (tessellation < 1 || tessellation > 64) {
    throw Error("icosahedron_basis: tessellation " + std::to_string(tessellation) +
                " is outside 1..64 (mip-NeRF 360 uses 2: 21 directions)");
  }
  const auto points = tessellated_sphere(tessellation);
  std::vector<Vec> basis;
  for (size_t i = 0; i < points.size(); ++i) {
    // Kept when its antipode comes at or after it (the official keeps rows with a match in the upper triangle).
    bool antipode_later = false;
    for (size_t j = i; j < points.size(); ++j) {
      const Vec minus{-points[j][0], -points[j][1], -points[j][2]};
      antipode_later = antipode_later || squared_distance(points[i], minus) < kSamePointSq;
    }
    if (antipode_later) basis.push_back({points[i][2], points[i][1], points[i][0]});
  }
  return basis;
}

std::vector<float> icosahedron_basis_floats(int tessellation) {
  std::vector<float> out;
  for (const auto& direction : icosahedron_basis(tessellation)) {
    for (double x : direction) out.push_back(static_cast<float>(x));
  }
  return out;
}

}  // namespace mipnerf
