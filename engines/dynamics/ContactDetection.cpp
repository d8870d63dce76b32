#include "dynamics/ContactDetection.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

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

Vec3i floorDiv(const Vec3& p, const Vec3& h) {
  return Vec3i(static_cast<int>(std::floor(p.x() / h.x())), static_cast<int>(std::floor(p.y() / h.y())),
               static_cast<int>(std::floor(p.z() / h.z())));
}

// Members sorted by the cell they fall in (counting sort), as in a classic linked-cell list.
struct CellGrid {
  Vec3i n;
  std::vector<int> begin, items;
  int index(int x, int y, int z) const { return (z * n.y() + y) * n.x() + x; }
};

}  // namespace

bool ContactDetection::needsRebuild(const Scene& s) const {
  if (s.detectionInvalid || refPos_.size() != s.members.pos.size()) return true;
  const Vec3 scale = s.cell.size.cwiseQuotient(refSize_);
  Real maxDisp2 = 0, maxGrow = 0;
  const int nm = s.members.size();
  for (int m = 0; m < nm; ++m) {
    maxDisp2 = std::max(maxDisp2, (s.members.pos[m] - refPos_[m].cwiseProduct(scale)).squaredNorm());
    maxGrow = std::max(maxGrow, s.members.radius[m] - refRadius_[m]);
  }
  // A pair's gap shrinks at most by both members' own displacements, both radius increases,
  // and the cell's relative change times the longest listed branch (2 r_max + skin).
  const Real affine = (scale.array() - 1.0).abs().maxCoeff() * (2.0 * s.maxRadius() + skin_);
  return 2.0 * std::sqrt(maxDisp2) + 2.0 * maxGrow + affine >= skin_;
}

void ContactDetection::apply(Scene& s) {
  if (needsRebuild(s)) rebuild(s);
}

void ContactDetection::rebuild(Scene& s) {
  s.validate();
  Bodies& B = s.bodies;
  Contacts& C = s.contacts;
  const Vec3 h = s.cell.size;
  const int nb = B.size();

  // 1. Wrap body centres into the cell and carry the old pairs' image shifts along.
  std::vector<Vec3i> wrap(nb);
  for (int b = 0; b < nb; ++b) {
    wrap[b] = floorDiv(B.pos[b], h);
    B.pos[b] -= wrap[b].cast<Real>().cwiseProduct(h);
  }
  for (int c = 0; c < C.size(); ++c) C.shift[c] += wrap[C.b2[c]] - wrap[C.b1[c]];
  s.refreshMembers();

  // 2. Cell grid with cells no smaller than the interaction range.
  const Members& M = s.members;
  const int nm = M.size();
  const Real rmax = s.maxRadius();
  skin_ = skinFactor * rmax;
  const Real range = 2.0 * rmax + skin_;
  CellGrid g;
  for (int k = 0; k < 3; ++k) g.n[k] = static_cast<int>(std::floor(h[k] / range));
  // Fewer than three cells along an axis is fine: the neighbour scan then visits the same cell
  // under different periodic images, each one once. Only a cell shorter than the range fails.
  require(g.n.minCoeff() >= 1,
          "the periodic cell is smaller than the interaction range 2 r_max + skin; use more particles");
  std::vector<Vec3i> image(nm);   // member m sits at wrapped position pos - image*h
  std::vector<Vec3> wrapped(nm);
  std::vector<Vec3i> cellOf(nm);
  g.begin.assign(g.n.prod() + 1, 0);
  for (int m = 0; m < nm; ++m) {
    image[m] = floorDiv(M.pos[m], h);
    wrapped[m] = M.pos[m] - image[m].cast<Real>().cwiseProduct(h);
    for (int k = 0; k < 3; ++k)
      cellOf[m][k] = std::min(g.n[k] - 1, std::max(0, static_cast<int>(wrapped[m][k] / h[k] * g.n[k])));
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
#pragma omp parallel
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
            const Vec3 shiftVec = sh.cast<Real>().cwiseProduct(h);
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

  // 4. New arrays, keeping the history (shear force, normal) of pairs already listed.
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
      N.shift[c] = p.shift;
      N.rbar[c] = 2.0 * M.radius[p.m1] * M.radius[p.m2] / (M.radius[p.m1] + M.radius[p.m2]);
      if (old < nold && C.m1[old] == p.m1 && C.m2[old] == p.m2 && C.shift[old] == p.shift) {
        N.normal[c] = C.normal[old]; N.branch[c] = C.branch[old]; N.overlap[c] = C.overlap[old];
        N.normalForce[c] = C.normalForce[old]; N.shearForce[c] = C.shearForce[old];
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
  N.incBegin.assign(nb + 1, 0);
  for (int k = 0; k < N.size(); ++k) { ++N.incBegin[N.b1[k] + 1]; ++N.incBegin[N.b2[k] + 1]; }
  std::partial_sum(N.incBegin.begin(), N.incBegin.end(), N.incBegin.begin());
  N.incidence.resize(2 * N.size());
  {
    std::vector<int> fill(N.incBegin.begin(), N.incBegin.end() - 1);
    for (int k = 0; k < N.size(); ++k) {
      N.incidence[fill[N.b1[k]]++] = ~k;
      N.incidence[fill[N.b2[k]]++] = k;
    }
  }
  C = std::move(N);

  refPos_ = M.pos;
  refRadius_ = M.radius;
  refSize_ = h;
  s.detectionInvalid = false;
  ++rebuilds;
}

}  // namespace trueaniso
