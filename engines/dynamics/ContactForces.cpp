#include "dynamics/ContactForces.hpp"

#include <algorithm>
#include <cmath>

#include "core/Parallel.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace trueaniso {

template <bool Clumps, bool Rotations, bool Sheared, bool Rolling>
void ContactForces::compute(Scene& s, const HertzMindlin& law) {
  Contacts& C = s.contacts;
  Bodies& B = s.bodies;
  const Members& M = s.members;
  // Orthorhombic cells act axis by axis (3 products where a sheared cell needs 9): image
  // offsets hSize k and the affine relative velocity L branch.
  const Mat3 hSize = s.cell.hSize, L = s.cell.velGrad;
  const Vec3 h = hSize.diagonal(), rate = L.diagonal();
  const Real dt = s.dt;
  const int nc = C.size(), nb = B.size();
  int nthreads = 1;
#ifdef _OPENMP
  nthreads = omp_get_max_threads();
#endif
  forceBuffers_.resize(nthreads);
  torqueBuffers_.resize(nthreads);
  static_assert(!Rolling || (Rotations && !Clumps), "rolling resistance acts on free single spheres only");
  long sliding = 0, rollingAtCap = 0;  // the second is only counted with Rolling
  // The team may be smaller than asked (OMP_DYNAMIC, nesting): only the buffers of threads that
  // ran this step hold this step's forces, so only they are summed below.
  int team = 1;

#pragma omp parallel reduction(+ : sliding) if (worthThreads(nc))
  {
    int t = 0;
#ifdef _OPENMP
    t = omp_get_thread_num();
#pragma omp single nowait
    team = omp_get_num_threads();
#endif
    Vec3* F;
    Vec3* T;
    if (t == 0) {
      F = B.force.data();
      T = B.torque.data();
    } else {
      forceBuffers_[t].resize(nb);
      torqueBuffers_[t].resize(nb);
      F = forceBuffers_[t].data();
      T = torqueBuffers_[t].data();
    }
    std::fill(F, F + nb, Vec3::Zero());
    if (Rotations) std::fill(T, T + nb, Vec3::Zero());
    long rollingCappedHere = 0;

    // This thread's contacts: the partition of libgomp's schedule(static), which the loop had,
    // written out so that the loop can walk them in batches (below). Any partition is correct;
    // this one keeps the bits of earlier runs with several threads.
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_num_threads();
#endif
    const int share = nc / threads, extra = nc % threads;
    const int lo = t < extra ? t * (share + 1) : t * share + extra;
    const int hi = lo + share + (t < extra ? 1 : 0);
    // Two passes over each batch of kBatch pairs: the geometry of every pair (the square root and
    // division of the distance), then the law and the forces of the touching ones. The first
    // pass's iterations are short and independent, so the processor overlaps their sqrt/division
    // chains, which one iteration of ~250 instructions did not let it do. Forces are added in
    // pair order as before: the same bits. Measured against the single loop (bench_builds.py,
    // docs/benchmarks.md): +6 to +15 % at 4000-16,000 spheres, none resolved at 32,000; a third
    // pass for the force additions and a branchless first pass measured no better.
    constexpr int kBatch = 32;
    struct Touch {  // a touching pair of the batch and its geometry
      Vec3 n, d;
      Real delta;
      int c;
    };
    Touch touch[kBatch];
    for (int c0 = lo; c0 < hi; c0 += kBatch) {
      const int c1 = std::min(hi, c0 + kBatch);
      int m = 0;
      for (int c = c0; c < c1; ++c) {
        const int i = C.m1[c], j = C.m2[c];
        const int a = Clumps ? C.b1[c] : i, b = Clumps ? C.b2[c] : j;
        const Vec3 sh = Sheared ? Vec3(hSize * C.shift[c].cast<Real>()) : Vec3(C.shift[c].cast<Real>().cwiseProduct(h));
        const Vec3& pi = Clumps ? M.pos[i] : B.pos[a];
        const Vec3 pj = (Clumps ? M.pos[j] : B.pos[b]) + sh;
        const Vec3 d = pj - pi;
        const Real rsum = M.radius[i] + M.radius[j];
        const Real dist2 = d.squaredNorm();
        if (dist2 >= rsum * rsum) {  // not touching: a contact ends and forgets its history
          if (C.normalForce[c] != 0) {
            C.normalForce[c] = 0;
            C.shearForce[c].setZero();
            if constexpr (Rolling) C.rollingMoment[c].setZero();
          }
          C.overlap[c] = rsum - std::sqrt(dist2);
          continue;
        }
        const Real dist = std::sqrt(dist2);
        Touch& q = touch[m++];
        q.n = d * (1.0 / dist);
        q.d = d;
        q.delta = rsum - dist;
        q.c = c;
      }
      for (int k = 0; k < m; ++k) {
        const int c = touch[k].c;
        const Vec3& n = touch[k].n;
        const Real delta = touch[k].delta;
        const int i = C.m1[c], j = C.m2[c];
        const int a = Clumps ? C.b1[c] : i, b = Clumps ? C.b2[c] : j;
        const Vec3 sh = Sheared ? Vec3(hSize * C.shift[c].cast<Real>()) : Vec3(C.shift[c].cast<Real>().cwiseProduct(h));
        const Real ri = M.radius[i], rj = M.radius[j];
        const Vec3 branch = Clumps ? Vec3(B.pos[b] + sh - B.pos[a]) : touch[k].d;

        // Lever arms from the body centres to the contact point, mid-overlap as in YADE's ScGeom.
        const Real arm1len = ri - 0.5 * delta, arm2len = rj - 0.5 * delta;
        // Velocities are fluctuations: the affine field adds L (x_b - x_a) = L branch.
        Vec3 vrel = B.vel[b] - B.vel[a] + (Sheared ? Vec3(L * branch) : Vec3(rate.cwiseProduct(branch)));
        Vec3 arm1, arm2;
        Real twist = 0;
        if (Rotations) {
          // (x + sh) - sh as before, which is not always x in floating point.
          arm1 = (Clumps ? Vec3(M.pos[i] - B.pos[a]) : Vec3::Zero()) + arm1len * n;
          arm2 = (Clumps ? Vec3(Vec3(M.pos[j] + sh) - sh - B.pos[b]) : Vec3::Zero()) - arm2len * n;
          vrel += B.angVel[b].cross(arm2) - B.angVel[a].cross(arm1);
          twist = 0.5 * dt * n.dot(B.angVel[a] + B.angVel[b]);
        }
        const Vec3 dus = (vrel - n.dot(vrel) * n) * dt;
        const HertzMindlin::Response r =
            law.evaluate(delta, C.rbar[c], n, C.normalForce[c] > 0, C.normal[c], C.shearForce[c], dus, twist);
        if (r.sliding) ++sliding;
        if constexpr (Rolling) {
          // Relative rolling rotation of the step: the spin difference off the normal (the part
          // along n is twist, which this sub-model does not resist).
          const Vec3 dw = (B.angVel[b] - B.angVel[a]) * dt;
          const Real ks = law.shearStiffness(HertzMindlin::normalStiffness(r.N, delta));
          bool capped;
          const Vec3 Mr = law.rollingMoment(C.rbar[c], r.N, ks, n, C.normalForce[c] > 0, C.normal[c], C.rollingMoment[c],
                                 dw - n.dot(dw) * n, twist, capped);
          if (capped) ++rollingCappedHere;
          C.rollingMoment[c] = Mr;
          T[a] -= Mr;  // the moment on body b, its opposite on body a
          T[b] += Mr;
        }

        C.normal[c] = n;
        C.branch[c] = branch;
        C.overlap[c] = delta;
        C.normalForce[c] = r.N;
        C.shearForce[c] = r.Fs;
        const Vec3 Fc = r.N * n + r.Fs;  // force on body b; body a receives -Fc
        F[a] -= Fc;
        F[b] += Fc;
        if (Rotations) {
          T[a] -= arm1.cross(Fc);
          T[b] += arm2.cross(Fc);
        }
      }
    }
    // Not a reduction clause: that would change the paper's loop (Rolling false) too.
    if constexpr (Rolling) {
#pragma omp atomic
      rollingAtCap += rollingCappedHere;
    }
  }
  slidingContacts = sliding;
  rollingCapped = rollingAtCap;
  // Thread buffers into the bodies' arrays, in thread order.
  for (int t = 1; t < team; ++t) {
    const std::vector<Vec3>& Ft = forceBuffers_[t];
    const std::vector<Vec3>& Tt = torqueBuffers_[t];
#pragma omp parallel for schedule(static) if (worthThreads(nb))
    for (int q = 0; q < nb; ++q) {
      B.force[q] += Ft[q];
      if (Rotations) B.torque[q] += Tt[q];
    }
  }
  if (!Rotations) std::fill(B.torque.begin(), B.torque.end(), Vec3::Zero());
}

void ContactForces::apply(Scene& s) {
  require(!s.detectionInvalid, "contact forces need an up-to-date contact list: run ContactDetection first");
  const HertzMindlin law(s.material);
  const bool clumps = s.hasClumps(), rot = !s.blockRotations;
  if (s.material.rolling()) {  // beta and eta_r were validated with the scene at the detection
    require(!clumps, "rolling resistance is modelled between single spheres only, not for clumps: set the "
                     "rolling stiffness factor to 0");
    // Blocked rotations: no relative rotation, no rolling moment; the paper's loop below.
    if (rot) {
      if (s.cell.orthorhombic()) compute<false, true, false, true>(s, law);
      else compute<false, true, true, true>(s, law);
      return;
    }
  }
  if (!s.cell.orthorhombic()) {
    if (clumps) {
      if (rot) compute<true, true, true>(s, law); else compute<true, false, true>(s, law);
    } else {
      if (rot) compute<false, true, true>(s, law); else compute<false, false, true>(s, law);
    }
  } else if (clumps) {
    if (rot) compute<true, true, false>(s, law); else compute<true, false, false>(s, law);
  } else {
    if (rot) compute<false, true, false>(s, law); else compute<false, false, false>(s, law);
  }
}

}  // namespace trueaniso
