#pragma once
// Candidate pairs from the Verlet list and the contacts among them, as flat arrays walked in
// order by the force loop. A pair is a contact while its normal force is > 0. Pairs persist
// between detections so the tangential force keeps its history.
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include "core/Types.hpp"

namespace trueaniso {

struct Contacts {
  // Pair identity: member spheres m1 < m2, their bodies, and the periodic image of m2
  // (member positions are unwrapped, so this stays valid as the bodies move).
  std::vector<int> m1, m2, b1, b2;
  std::vector<Vec3i> shift;
  // The same image as one byte, the index of the force loop's table of image offsets
  // (imageIndex): the loop reads a byte a pair instead of 12 and looks its offset up instead of
  // multiplying the cell by it. Written by the detection with the list; whatever else changes a
  // shift (a flip, a renumbering, an import) invalidates the detection, which writes them anew.
  std::vector<std::uint8_t> image;
  std::vector<Real> rbar;        // Eq. (7): 2 r1 r2 / (r1 + r2)

  // State of the last force evaluation.
  std::vector<Vec3> normal;      // unit n from sphere 1 to sphere 2
  std::vector<Real> overlap;     // delta, <= 0 when not touching
  std::vector<Real> normalForce; // N >= 0
  std::vector<Vec3> shearForce;  // tangential force on sphere 2 (history variable)
  // Rolling moment on sphere 2 (history variable of the rolling sub-model, in the tangent plane);
  // stays zero unless the material has rolling resistance (Material::rolling).
  std::vector<Vec3> rollingMoment;

  // The configuration the forces were last evaluated in (ContactForces): the body centres and the
  // cell's hSize. A contact's branch vector L, between the two body centres, is computed from
  // them by branch(c), the force loop's own expression, instead of being stored per pair: the
  // loop needs it only for its touching pairs' affine velocity and measures, and 24 bytes a
  // touching pair written every step cost more than one copy of the centres
  // (docs/studies/benchmarks.md, "The branch vector on demand").
  // Empty until a force evaluation: a contact history set from a file or from YADE has no branch.
  struct Evaluation {
    std::vector<Vec3> pos;
    Mat3 hSize = Mat3::Zero();
    bool sheared = false;  // images by the full hSize (a sheared cell), else by its diagonal
    // The offset of periodic image k in that cell, with the force loop's arithmetic.
    Vec3 image(const Vec3i& k) const {
      const Vec3 x = k.cast<Real>();
      return sheared ? Vec3(hSize * x) : Vec3(x.cwiseProduct(hSize.diagonal()));
    }
  } evaluation;

  // Whether the branch vectors are those of the nb bodies' last force evaluation.
  bool evaluated(int nb) const { return static_cast<int>(evaluation.pos.size()) == nb && nb > 0; }
  // A measure (named by `who`) of contacts that carry forces needs their branch vectors: refused
  // (InputError) when no force evaluation of these nb bodies has run, not summed with none.
  void requireEvaluated(int nb, const std::string& who) const {
    if (evaluated(nb)) return;
    for (int c = 0; c < size(); ++c)
      require(!active(c), who + ": the contacts carry forces but no force evaluation has run at these positions "
                                "(a contact history just set, e.g. a scene imported from YADE): evaluate the "
                                "forces first (trueaniso.dem.refresh(scene), or a step)");
  }
  // L of pair c, from body 1's centre to the image of body 2's (evaluated() must hold). The
  // arithmetic is the force loop's: the bits the loop used, on the baseline build; at x86-64-v3
  // the compiler may fuse it into the caller's multiply-adds otherwise than in the loop (1 ulp).
  Vec3 branch(int c) const {
    return evaluation.pos[b2[c]] + evaluation.image(shift[c]) - evaluation.pos[b1[c]];
  }

  // Incidence lists (pairs of each body) for per-body measures and the time step:
  // pairs of body b are incidence[incBegin[b] .. incBegin[b+1]), an entry c >= 0 means b is
  // side 2 of pair c, an entry ~c (< 0) means side 1.
  std::vector<int> incBegin, incidence;

  // The images the table holds: up to kImageReach cells away on each axis. The detection's pairs
  // are within one cell of each other's wrapped centre (two for members of clumps that stick out
  // of the cell); an image farther away means a cell not much wider than a particle, refused.
  static constexpr int kImageReach = 2, kImageSide = 2 * kImageReach + 1, kImages = kImageSide * kImageSide * kImageSide;
  static_assert(kImages <= 256, "an image index is one byte");
  static bool imageInReach(const Vec3i& k) { return k.cwiseAbs().maxCoeff() <= kImageReach; }
  static std::uint8_t imageIndex(const Vec3i& k) {
    return static_cast<std::uint8_t>((k.x() + kImageReach) + kImageSide * ((k.y() + kImageReach) + kImageSide * (k.z() + kImageReach)));
  }
  static Vec3i imageOf(int index) {
    return Vec3i(index % kImageSide, (index / kImageSide) % kImageSide, index / (kImageSide * kImageSide)) -
           Vec3i::Constant(kImageReach);
  }

  int size() const { return static_cast<int>(m1.size()); }
  bool active(int c) const { return normalForce[c] > 0; }
  Vec3 force(int c) const { return normalForce[c] * normal[c] + shearForce[c]; }  // on body 2
  // The contact law's stiffnesses come from contact/HertzMindlin (normalStiffness(N, delta)).

  // The incidence lists of nb bodies from b1, b2 (each body's pairs in pair order).
  void buildIncidence(int nb) {
    incBegin.assign(nb + 1, 0);
    for (int k = 0; k < size(); ++k) { ++incBegin[b1[k] + 1]; ++incBegin[b2[k] + 1]; }
    std::partial_sum(incBegin.begin(), incBegin.end(), incBegin.begin());
    incidence.resize(2 * size());
    std::vector<int> fill(incBegin.begin(), incBegin.end() - 1);
    for (int k = 0; k < size(); ++k) {
      incidence[fill[b1[k]]++] = ~k;
      incidence[fill[b2[k]]++] = k;
    }
  }

  void resize(int n) {
    m1.resize(n); m2.resize(n); b1.resize(n); b2.resize(n); shift.resize(n); image.resize(n); rbar.resize(n);
    normal.resize(n, Vec3::Zero()); overlap.resize(n, 0.0);
    normalForce.resize(n, 0.0); shearForce.resize(n, Vec3::Zero());
    rollingMoment.resize(n, Vec3::Zero());
  }
};

}  // namespace trueaniso
