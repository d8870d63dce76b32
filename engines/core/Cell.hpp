#pragma once
// Periodic cell with a full 3x3 transformation, as YADE's Cell (hSize, refHSize, velGrad).
//
// The cell vectors a_1, a_2, a_3 are the columns of hSize; a point x has reduced coordinates
// s = hSize^-1 x and periodic images x + hSize k for integer k (a contact stores its k, the image
// shift). Body positions are never wrapped between detections, so a contact's k stays valid as
// bodies and the cell move. The affine field of the deformation is v = velGrad x; bodies store
// their velocity about it. The servos prescribe a symmetric velGrad (no spin), so the cell's axes
// stay the frame the stresses are given in; a velGrad with spin (from YADE) is integrated as well.
//
// A cell that shears far becomes too thin for the contact grid. A flip changes the cell vectors
// by an integer matrix M of determinant 1 (hSize -> hSize M): the same lattice of images, the
// same periodic medium, shorter and more orthogonal vectors. refHSize is remapped with it, so
// the deformation gradient F = hSize refHSize^-1 and every strain are properties of the motion
// alone; contacts' shifts are remapped by M^-1 (dynamics/CellFlip.hpp).
//
// Scenes that do not need shear keep hSize and velGrad diagonal; the hot loops then take the
// orthorhombic path (orthorhombic()), which costs what the diagonal cell always cost.
#include "core/Types.hpp"
#include "core/Voigt.hpp"

namespace trueaniso {

using Mat3i = Eigen::Matrix3i;

struct Cell {
  Mat3 hSize = Mat3::Identity();      // columns: the cell vectors (m)
  Mat3 refHSize = Mat3::Identity();   // the cell at zero strain
  Mat3 velGrad = Mat3::Zero();        // L of the affine velocity field (1/s)

  // An orthorhombic box of the given edge lengths, also the reference; velGrad is left as it is.
  void setBox(const Vec3& size) { hSize = refHSize = size.asDiagonal(); }

  Real volume() const { return hSize.determinant(); }
  // hSize and velGrad diagonal: images and the affine field act axis by axis (the fast path).
  bool orthorhombic() const { return isDiagonal(hSize) && isDiagonal(velGrad); }
  // Image displacement of a periodic shift.
  Vec3 shiftVector(const Vec3i& s) const { return hSize * s.cast<Real>(); }
  // Deformation gradient since the reference, unchanged by flips.
  Mat3 deformation() const { return hSize * refHSize.inverse(); }
  // Logarithmic strain since the reference (strainBetween below), Voigt, compression positive.
  Vec6 strain() const;
  // Distance between opposite faces, V / |a_j x a_k|: what a contact grid must fit in.
  Vec3 widths() const;

  // Throws InputError for a cell that cannot be simulated: non-finite, singular (vectors nearly
  // coplanar) or inverted (a left-handed set of vectors, det hSize < 0), the same for the lattice
  // of refHSize (its vectors themselves skew with every flip, refused only where F = hSize
  // refHSize^-1 would lose more than about 2e-7 to round-off), or a non-finite velGrad.
  void validate() const;

  // The unimodular integer M that size-reduces the cell vectors (|a_i . a_j| <= |a_i|^2 / 2 for
  // every pair after hSize M), or the identity when no pair exceeds `threshold` (> 1/2, so that a
  // cell sheared back and forth around 1/2 does not flip at every detection).
  Mat3i reduction(Real threshold) const;
  // hSize -> hSize M, refHSize -> refHSize M (M unimodular); contacts are the caller's.
  void flip(const Mat3i& M);

  static bool isDiagonal(const Mat3& m) {
    return m(0, 1) == 0 && m(0, 2) == 0 && m(1, 0) == 0 && m(1, 2) == 0 && m(2, 0) == 0 && m(2, 1) == 0;
  }
};

// Strain of the deformation from F0 to F1: -sym(log(F1 F0^-1)) as a Voigt vector with
// engineering shears, compression positive (the sign of the stresses). For a diagonal deformation
// it is -ln(h_k / h0_k) exactly; for any small increment it is the symmetric displacement gradient
// to second order, which is the strain the static stiffness is defined against. A probe takes its
// strain increments between its own reference and now, so the path's earlier strains (a few per
// cent, anisotropic) do not enter its shear increments.
Vec6 strainBetween(const Mat3& F0, const Mat3& F1);

// Inverse of an integer matrix of determinant +-1 (exact, in integers).
Mat3i unimodularInverse(const Mat3i& M);

}  // namespace trueaniso
