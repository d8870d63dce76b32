#include "dynamics/CellFlip.hpp"

namespace trueaniso {

void flipCell(Scene& s, const Mat3i& M) {
  const Mat3i inverse = unimodularInverse(M);
  s.cell.flip(M);
  for (Vec3i& k : s.contacts.shift) k = inverse * k;
  // The branch vectors' images the same vectors, in the flipped cell's terms, until the next forces.
  Contacts::Evaluation& e = s.contacts.evaluation;
  e.hSize = e.hSize * M.cast<Real>();
  e.sheared = true;
  s.detectionInvalid = true;
}

Mat3i flipIfSheared(Scene& s, Real threshold) {
  const Mat3i M = s.cell.reduction(threshold);
  if (M != Mat3i::Identity()) flipCell(s, M);
  return M;
}

}  // namespace trueaniso
