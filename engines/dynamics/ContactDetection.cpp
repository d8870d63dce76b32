#include "dynamics/ContactDetection.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <tuple>

#include "core/Parallel.hpp"
#include "dynamics/CellFlip.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace trueaniso {

namespace {

struct Candidate {
  int m1, m2;
  Vec3i shift;
};

bool pairLess(int a1, int a2, const Vec3i& sa, int b1, int b2, const Vec3i& sb) {
  return std::tie(a1, a2, sa[0], sa[1], sa[2]) < std::tie(b1, b2, sb[0], sb[1], sb[2]);
}

// Reduced coordinates of the cell: x = hSize s. An orthorhombic cell divides axis by axis, as
// the diagonal cell always did, so its images and bins are bit-for-bit those of before.
struct Frame {
  Mat3 h, hinv;
  Vec3 diag;
  bool ortho;
  explicit Frame(const Mat3& hSize)
      : h(hSize), hinv(hSize.inverse()), diag(hSize.diagonal()), ortho(Cell::isDiagonal(hSize)) {}
  Vec3 reduced(const Vec3& x) const { return ortho ? Vec3(x.cwiseQuotient(diag)) : Vec3(hinv * x); }
  Vec3 offset(const Vec3i& k) const {
    return ortho ? Vec3(k.cast<Real>().cwiseProduct(diag)) : Vec3(h * k.cast<Real>());
  }
  Vec3i image(const Vec3& x) const {  // the cell copy x lies in: floor of its reduced coordinates
    const Vec3 s = reduced(x);
    return Vec3i(static_cast<int>(std::floor(s.x())), static_cast<int>(std::floor(s.y())),
                 static_cast<int>(std::floor(s.z())));
  }
};

// Members sorted by the cell they fall in (counting sort), as in a classic linked-cell list.
struct CellGrid {
  Vec3i n;
  std::vector<int> begin, items;
  int index(int x, int y, int z) const { return (z * n.y() + y) * n.x() + x; }
};

}  // namespace

bool ContactDetection::needsRebuild(const Scene& s) const {
  if (s.detectionInvalid || refPos_.size() != s.members.pos.size()) return true;
  // T: the cell's affine map since the last build. Members are compared with where the affine
  // field alone would have carried them.
  const bool diagonal = Cell::isDiagonal(s.cell.hSize) && Cell::isDiagonal(refHSize_);
  const Mat3 T = diagonal ? Mat3(s.cell.hSize.diagonal().cwiseQuotient(refHSize_.diagonal()).asDiagonal())
                          : Mat3(s.cell.hSize * refHSize_.inverse());
  const Vec3 scale = T.diagonal();
  // One pass over the members, on the team: it runs every step, and as two serial loops it was
  // work the second thread waited through (perf, 2 threads, 16,000 spheres: libgomp's waits 12.5 %
  // of the samples with these loops and the integrator's copy serial, 10.2 % without). A maximum is
  // exact in any order, so the result is the serial loops'.
  Real maxDisp2 = 0, maxGrow = 0, rmax = 0;
  const int nm = s.members.size();
  const Vec3* const pos = s.members.pos.data();
  const Real* const radius = s.members.radius.data();
  const Vec3* const ref = refPos_.data();
  const Real* const refRadius = refRadius_.data();
#pragma omp parallel for schedule(static) reduction(max : maxDisp2, maxGrow, rmax) if (worthThreadsBeside(nm, s.contacts.size()))
  for (int m = 0; m < nm; ++m) {
    const Vec3 carried = diagonal ? Vec3(ref[m].cwiseProduct(scale)) : Vec3(T * ref[m]);
    maxDisp2 = std::max(maxDisp2, (pos[m] - carried).squaredNorm());
    maxGrow = std::max(maxGrow, radius[m] - refRadius[m]);
    rmax = std::max(rmax, radius[m]);
  }
  // A pair's gap shrinks at most by both members' own displacements, both radius increases,
  // and |T - I| (the spectral norm: the largest stretch of a branch by the affine map) times the
  // longest listed branch (2 r_max + skin); longer branches keep a longer gap.
  const Mat3 D = T - Mat3::Identity();
  const Real stretch = diagonal ? D.diagonal().cwiseAbs().maxCoeff()
                                : std::sqrt(Eigen::SelfAdjointEigenSolver<Mat3>(D.transpose() * D,
                                                                               Eigen::EigenvaluesOnly)
                                                .eigenvalues()
                                                .maxCoeff());
  const Real affine = stretch * (2.0 * rmax + skin_);  // rmax: Scene::maxRadius, from the pass above
  return 2.0 * std::sqrt(maxDisp2) + 2.0 * maxGrow + affine >= skin_;
}

void ContactDetection::apply(Scene& s) {
  if (needsRebuild(s)) rebuild(s);
}

void ContactDetection::rebuild(Scene& s) {
  s.validate();
  if (allowFlip && flipIfSheared(s, flipThreshold) != Mat3i::Identity()) ++flips;
  Bodies& B = s.bodies;
  Contacts& C = s.contacts;
  const Frame frame(s.cell.hSize);
  const int nb = B.size();

  // 1. Wrap body centres into the cell and carry the old pairs' image shifts along.
  std::vector<Vec3i> wrap(nb);
  for (int b = 0; b < nb; ++b) {
    wrap[b] = frame.image(B.pos[b]);
    B.pos[b] -= frame.offset(wrap[b]);
  }
  for (int c = 0; c < C.size(); ++c) C.shift[c] += wrap[C.b2[c]] - wrap[C.b1[c]];
  if (C.evaluated(nb))  // the last evaluation's centres the same way, so each branch stays its vector
    for (int b = 0; b < nb; ++b)
      if (wrap[b] != Vec3i::Zero()) C.evaluation.pos[b] -= C.evaluation.image(wrap[b]);
  s.refreshMembers();

  // 2. Cell grid in reduced coordinates, with bins no thinner than the interaction range: two
  // points closer than the range differ in reduced coordinate k by less than range / width_k
  // (the row k of hSize^-1 has length 1 / width_k), so by at most one bin.
  const Members& M = s.members;
  const int nm = M.size();
  const Real rmax = s.maxRadius();
  skin_ = skinFactor * rmax;
  const Real range = 2.0 * rmax + skin_;
  const Vec3 width = s.cell.widths();
  CellGrid g;
  for (int k = 0; k < 3; ++k) g.n[k] = static_cast<int>(std::floor(width[k] / range));
  // Fewer than three cells along an axis is fine: the neighbour scan then visits the same cell
  // under different periodic images, each one once. Only a cell thinner than the range fails.
  require(g.n.minCoeff() >= 1,
          "the periodic cell is thinner than the interaction range 2 r_max + skin; use more particles");
  std::vector<Vec3i> image(nm);   // member m sits at wrapped position pos - hSize image
  std::vector<Vec3> wrapped(nm);
  std::vector<Vec3i> cellOf(nm);
  g.begin.assign(g.n.prod() + 1, 0);
  for (int m = 0; m < nm; ++m) {
    image[m] = frame.image(M.pos[m]);
    wrapped[m] = M.pos[m] - frame.offset(image[m]);
    const Vec3 r = frame.reduced(wrapped[m]);
    for (int k = 0; k < 3; ++k)
      cellOf[m][k] = std::min(g.n[k] - 1, std::max(0, static_cast<int>(r[k] * g.n[k])));
    ++g.begin[g.index(cellOf[m].x(), cellOf[m].y(), cellOf[m].z()) + 1];
  }
  std::partial_sum(g.begin.begin(), g.begin.end(), g.begin.begin());
  g.items.resize(nm);
  {
    std::vector<int> fill(g.begin.begin(), g.begin.end() - 1);
    for (int m = 0; m < nm; ++m) g.items[fill[g.index(cellOf[m].x(), cellOf[m].y(), cellOf[m].z())]++] = m;
  }

  // 3. Candidate pairs, found from the lower index; per-thread lists joined in index order.
  int nthreads = 1;
#ifdef _OPENMP
  nthreads = omp_get_max_threads();
#endif
  std::vector<std::vector<Candidate>> found(nthreads);
#pragma omp parallel if (worthThreadsBeside(nm, C.size()))
  {
    int t = 0;
#ifdef _OPENMP
    t = omp_get_thread_num();
#endif
    std::vector<Candidate>& out = found[t];
#pragma omp for schedule(static)
    for (int i = 0; i < nm; ++i) {
      const size_t first = out.size();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            Vec3i c = cellOf[i] + Vec3i(dx, dy, dz), sh = Vec3i::Zero();
            for (int k = 0; k < 3; ++k) {
              if (c[k] < 0) { c[k] += g.n[k]; sh[k] = -1; }
              else if (c[k] >= g.n[k]) { c[k] -= g.n[k]; sh[k] = 1; }
            }
            const int cell = g.index(c.x(), c.y(), c.z());
            const Vec3 shiftVec = frame.offset(sh);
            for (int q = g.begin[cell]; q < g.begin[cell + 1]; ++q) {
              const int j = g.items[q];
              if (j <= i || M.body[j] == M.body[i]) continue;
              const Real reach = M.radius[i] + M.radius[j] + skin_;
              if ((wrapped[j] + shiftVec - wrapped[i]).squaredNorm() < reach * reach)
                out.push_back({i, j, sh + image[i] - image[j]});
            }
          }
      std::sort(out.begin() + first, out.end(), [](const Candidate& a, const Candidate& b) {
        return pairLess(a.m1, a.m2, a.shift, b.m1, b.m2, b.shift);
      });
    }
  }

  // 4. New arrays, keeping the history (shear force, rolling moment, normal) of pairs already listed.
  Contacts N;
  size_t total = 0;
  for (auto& f : found) total += f.size();
  N.resize(static_cast<int>(total));
  int c = 0, old = 0;
  const int nold = C.size();
  long lost = 0;
  for (auto& f : found)
    for (const Candidate& p : f) {
      while (old < nold && pairLess(C.m1[old], C.m2[old], C.shift[old], p.m1, p.m2, p.shift)) {
        if (C.normalForce[old] > 0) ++lost;
        ++old;
      }
      N.m1[c] = p.m1; N.m2[c] = p.m2; N.b1[c] = M.body[p.m1]; N.b2[c] = M.body[p.m2];
      require(Contacts::imageInReach(p.shift),
              "ContactDetection: a pair across more than " + std::to_string(Contacts::kImageReach) +
                  " periodic cells: the cell is too small for these particles (make it wider than a few particle diameters)");
      N.shift[c] = p.shift;
      N.image[c] = Contacts::imageIndex(p.shift);
      N.rbar[c] = 2.0 * M.radius[p.m1] * M.radius[p.m2] / (M.radius[p.m1] + M.radius[p.m2]);
      if (old < nold && C.m1[old] == p.m1 && C.m2[old] == p.m2 && C.shift[old] == p.shift) {
        N.normal[c] = C.normal[old]; N.overlap[c] = C.overlap[old];
        N.normalForce[c] = C.normalForce[old]; N.shearForce[c] = C.shearForce[old];
        N.rollingMoment[c] = C.rollingMoment[old];
        ++old;
      } else {
        const Vec3 d = M.pos[p.m2] + s.cell.shiftVector(p.shift) - M.pos[p.m1];
        N.normal[c] = d.normalized();
      }
      ++c;
    }
  for (; old < nold; ++old)
    if (C.normalForce[old] > 0) ++lost;
  lostContacts += lost;

  // 5. Incidence lists (body -> its pairs) so forces are gathered per body, conflict-free.
  N.buildIncidence(nb);
  N.evaluation = std::move(C.evaluation);  // the branch vectors of the pairs kept, until the forces
  C = std::move(N);

  refPos_ = M.pos;
  refRadius_ = M.radius;
  refHSize_ = frame.h;
  s.detectionInvalid = false;
  ++rebuilds;
}

}  // namespace trueaniso
