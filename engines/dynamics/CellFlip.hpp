#pragma once
// Re-mapping of a sheared cell (a "flip"), as LAMMPS's fix deform (flip yes) and YADE's
// Cell.flipCell do: hSize -> hSize M with M an integer matrix of determinant 1, the same periodic
// medium described by shorter, more orthogonal cell vectors. Body positions are unchanged (they
// are Cartesian and unwrapped); every contact keeps its identity and history, its image shift
// k remapped to M^-1 k so that its image offset hSize k is the same vector.
#include "core/Scene.hpp"

namespace trueaniso {

// Flip by M (unimodular), remapping the contacts' shifts; the contact list must be rebuilt after.
void flipCell(Scene& scene, const Mat3i& M);

// Flip when some pair of cell vectors has |a_i . a_j| > threshold |a_i|^2 (Cell::reduction).
// Returns the M applied (the identity when the cell was left as it is).
Mat3i flipIfSheared(Scene& scene, Real threshold);

}  // namespace trueaniso
