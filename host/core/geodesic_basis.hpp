// The directions mip-NeRF 360 projects contracted Gaussians onto before its IPE (Barron et al. 2022, §2 and the
// official multinerf geopoly.generate_basis): the vertices of an icosahedron whose faces are tessellated `v` times,
// pushed onto the unit sphere, with one of each antipodal pair kept (the other's projection would repeat the same
// features with the opposite sign). v = 2, the official default, gives 21 directions; with degrees 0..11 the encoding
// is 2·12·21 = 504 features.
//
// The order is the official's, which the MLP's first layer depends on (features index degree·K + direction): faces in
// the official list order, each face's barycentric weights (i, j, v − i − j) for i = 0..v, j = 0..v − i, a vertex
// first seen kept at its first place, the lower-placed one of each antipodal pair kept, and each vertex written
// (z, y, x) (the official reverses the coordinate axis: basis = verts[:, ::-1]).
#pragma once

#include <array>
#include <vector>

namespace mipnerf {

// The unit directions of the tessellated icosahedron's half (see above), in double; throws mipnerf::Error for v < 1.
std::vector<std::array<double, 3>> icosahedron_basis(int tessellation);

// The same directions as floats [K][3], the kernels' layout (the official's jnp.array of the float64 basis).
std::vector<float> icosahedron_basis_floats(int tessellation);

}  // namespace mipnerf
