#include "clump/ClumpTemplate.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <numeric>
#include <sstream>

#include "clump/UnionOfBalls.hpp"

namespace trueaniso {

namespace {
constexpr Real kPi = 3.14159265358979323846;
}

void validateClumpMembers(const std::vector<Vec3>& centres, const std::vector<Real>& radii) {
  require(!radii.empty(), "a clump needs at least one member");
  require(centres.size() == radii.size(), "a clump needs as many member centres as radii");
  const int n = static_cast<int>(radii.size());
  for (int k = 0; k < n; ++k) {
    std::ostringstream at;
    at << "clump member " << k << ": ";
    require(std::isfinite(radii[k]) && radii[k] > 0, at.str() + "radius must be a finite number > 0");
    require(centres[k].allFinite(), at.str() + "centre must be finite");
  }
  // Connected components of the overlap graph, by a flood fill from member 0.
  std::vector<char> reached(n, 0);
  std::vector<int> stack{0};
  reached[0] = 1;
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    for (int j = 0; j < n; ++j)
      if (!reached[j] && (centres[j] - centres[i]).norm() < radii[i] + radii[j]) {
        reached[j] = 1;
        stack.push_back(j);
      }
  }
  for (int k = 0; k < n; ++k)
    if (!reached[k]) {
      std::ostringstream msg;
      msg << "clump members do not form one body: member " << k
          << " does not overlap the others (a clump is a union of overlapping balls)";
      throw InputError(msg.str());
    }
}

Real ClumpTemplate::boundingRadius() const {
  Real r = 0;
  for (int k = 0; k < size(); ++k) r = std::max(r, offsets[k].norm() + radii[k]);
  return r;
}

Real ClumpTemplate::equivalentDiameter() const { return 2.0 * std::cbrt(3.0 * volume / (4.0 * kPi)); }

ClumpTemplate ClumpTemplate::scaled(Real f) const {
  require(std::isfinite(f) && f > 0, "clump template scale must be a finite number > 0");
  ClumpTemplate t = *this;
  for (Vec3& o : t.offsets) o *= f;
  for (Real& r : t.radii) r *= f;
  t.centroid *= f;
  t.volume *= f * f * f;
  t.inertia *= f * f * f * f * f;
  return t;
}

ClumpTemplate makeClumpTemplate(const std::vector<Vec3>& centres, const std::vector<Real>& radii, int levels) {
  validateClumpMembers(centres, radii);
  const UnionMoments m = unionOfBallsMoments(centres, radii, levels);
  ClumpTemplate t;
  t.volume = m.volume;
  t.volumeErrorEstimate = m.volumeErrorEstimate;
  t.centroid = m.first / m.volume;
  // Second moment about the centroid, then the inertia tensor per unit density: tr(J) 1 - J.
  const Mat3 J = m.second - m.volume * t.centroid * t.centroid.transpose();
  Mat3 I = J.trace() * Mat3::Identity() - J;
  I = 0.5 * (I + I.transpose());
  Eigen::SelfAdjointEigenSolver<Mat3> eig(I);  // ascending eigenvalues
  t.inertia = eig.eigenvalues();
  t.axes = eig.eigenvectors();
  if (t.axes.determinant() < 0) t.axes.col(2) *= -1.0;  // a rotation, not a reflection
  t.radii = radii;
  for (const Vec3& c : centres) t.offsets.push_back(t.axes.transpose() * (c - t.centroid));
  return t;
}

namespace {

// Scale-free description of a member set up to rigid motions: members ordered by (radius, sorted
// distances to the others), then the radii and the distance matrix in that order, all divided by
// the largest radius and rounded to 1e-9. Equal keys mean equal distance matrices (to 1e-9), hence
// congruent member sets; a congruent set may get another key when members tie (a second
// computation, never a wrong volume).
std::vector<int64_t> shapeKey(const std::vector<Vec3>& c, const std::vector<Real>& r, Real scale) {
  const int n = static_cast<int>(r.size());
  auto q = [&](Real x) { return static_cast<int64_t>(std::llround(x / scale * 1e9)); };
  std::vector<std::vector<int64_t>> desc(n);
  for (int i = 0; i < n; ++i) {
    std::vector<int64_t> d;
    for (int j = 0; j < n; ++j)
      if (j != i) d.push_back(q((c[j] - c[i]).norm()));
    std::sort(d.begin(), d.end());
    desc[i].push_back(q(r[i]));
    desc[i].insert(desc[i].end(), d.begin(), d.end());
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return desc[a] < desc[b]; });
  std::vector<int64_t> key{n};
  for (int i : order) key.push_back(q(r[i]));
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) key.push_back(q((c[order[b]] - c[order[a]]).norm()));
  return key;
}

}  // namespace

Real cachedClumpVolume(const std::vector<Vec3>& centres, const std::vector<Real>& radii) {
  validateClumpMembers(centres, radii);
  if (radii.size() == 1) return 4.0 / 3.0 * kPi * radii[0] * radii[0] * radii[0];
  static std::mutex lock;
  static std::map<std::vector<int64_t>, Real> unitVolume;  // volume at largest radius 1
  const Real scale = *std::max_element(radii.begin(), radii.end());
  const std::vector<int64_t> key = shapeKey(centres, radii, scale);
  {
    std::lock_guard<std::mutex> guard(lock);
    const auto it = unitVolume.find(key);
    if (it != unitVolume.end()) return it->second * scale * scale * scale;
  }
  const Real v = unionOfBallsMoments(centres, radii).volume / (scale * scale * scale);
  std::lock_guard<std::mutex> guard(lock);
  unitVolume.emplace(key, v);
  return v * scale * scale * scale;
}

}  // namespace trueaniso
