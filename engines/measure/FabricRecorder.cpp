#include "measure/FabricRecorder.hpp"

namespace trueaniso {

namespace {

void appendMatrix(std::vector<Real>& out, const Mat3& m) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.push_back(m(i, j));
}

}  // namespace

void FabricHistory::append(long st, Real t, const Fabric& f) {
  step.push_back(st);
  time.push_back(t);
  contacts.push_back(f.counts.contacts);
  particles.push_back(f.counts.particles);
  noContact.push_back(f.counts.noContact);
  oneContact.push_back(f.counts.oneContact);
  Zm.push_back(f.Zm);
  contactDensityEq36.push_back(f.contactDensityEq36());
  contactDensityCount.push_back(f.contactDensityCount());
  voidRatio.push_back(f.voidRatio);
  meanNormalForce.push_back(f.meanNormalForce);
  volume.push_back(f.volume);
  meanRadiusCubed.push_back(f.meanRadiusCubed);
  appendMatrix(R, f.R);
  appendMatrix(H, f.H);
  appendMatrix(B, f.B);
  // Mat9 row 3i+j, column 3k+l: row-major order over (row, column) is C order over [i][j][k][l].
  for (int a = 0; a < 9; ++a)
    for (int b = 0; b < 9; ++b) M.push_back(f.M(a, b));
}

void FabricHistory::reserve(int rows) {
  for (auto* v : {&step, &contacts, &particles, &noContact, &oneContact}) v->reserve(rows);
  for (auto* v : {&time, &Zm, &contactDensityEq36, &contactDensityCount, &voidRatio, &meanNormalForce,
                  &volume, &meanRadiusCubed})
    v->reserve(rows);
  for (auto* v : {&R, &H, &B}) v->reserve(9 * static_cast<size_t>(rows));
  M.reserve(81 * static_cast<size_t>(rows));
}

void FabricRecorder::apply(Scene& s) {
  last = fabric(s);
  history.append(s.step, s.time, last);
}

}  // namespace trueaniso
