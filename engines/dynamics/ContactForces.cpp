#include "dynamics/ContactForces.hpp"

#include <algorithm>
#include <cmath>

#include "core/Parallel.hpp"
#include "measure/CellLanes.hpp"
#include "measure/Reduce.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

// Vectors of four lanes (measure/CellLanes.hpp) are passed only to functions that are always
// inlined: GCC's note that such a call would change the ABI on the baseline does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace trueaniso {

template <bool Clumps, bool Rotations, bool Sheared, bool Rolling>
void ContactForces::compute(Scene& s, const HertzMindlin& law) {
  Contacts& C = s.contacts;
  Bodies& B = s.bodies;
  const Members& M = s.members;
  // Orthorhombic cells act axis by axis (3 products where a sheared cell needs 9): the affine
  // relative velocity L branch.
  const Mat3 hSize = s.cell.hSize, L = s.cell.velGrad;
  const Vec3 rate = L.diagonal();
  const Real dt = s.dt;
  const int nc = C.size(), nb = B.size();
  int nthreads = 1;
#ifdef _OPENMP
  nthreads = omp_get_max_threads();
#endif
  forceBuffers_.resize(nthreads);
  torqueBuffers_.resize(nthreads);
  // The cell measures' sums, in the steps an engine reads them (measure/CellSums.hpp): per block of
  // kSumBlock pairs and of kSumBlock bodies, each thread filling its own blocks, added in block order below.
  const bool measure = s.measured.wanted;
  const int pairBlocks = (nc + kSumBlock - 1) / kSumBlock, bodyBlocks = (nb + kSumBlock - 1) / kSumBlock;
  if (measure) {
    pairSums_.resize(pairBlocks);
    bodySums_.resize(bodyBlocks);
  }
  CellSums* const pairSums = pairSums_.data();
  Real* const bodySums = bodySums_.data();
  const Real ratio = law.shearToNormal();
  static_assert(!Rolling || (Rotations && !Clumps), "rolling resistance acts on free single spheres only");
  long sliding = 0, rollingAtCap = 0;  // the second is only counted with Rolling

  // The configuration of this evaluation, from which the branch vectors are read after it
  // (Contacts::branch): the cell here, the centres by the team below.
  C.evaluation.hSize = hSize;
  C.evaluation.sheared = Sheared;
  C.evaluation.pos.resize(nb);
  Vec3* const evaluatedPos = C.evaluation.pos.data();
  // The offset of every image a pair may have (Contacts::image indexes it) in this cell, once a
  // step instead of once a pair, by the evaluation's own arithmetic (Contacts::branch uses it too):
  // k's entries are integers of at most 2, so each term is exact, and the sum is the same with or
  // without FMA.
  Vec3 offsets[Contacts::kImages];
  for (int i = 0; i < Contacts::kImages; ++i) offsets[i] = C.evaluation.image(Contacts::imageOf(i));

#pragma omp parallel reduction(+ : sliding) if (worthThreads(nc))
  {
    int t = 0;
#ifdef _OPENMP
    t = omp_get_thread_num();
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
    {
      const Vec3* const centres = B.pos.data();
#pragma omp for schedule(static) nowait
      for (int b = 0; b < nb; ++b) evaluatedPos[b] = centres[b];
    }
    long rollingCappedHere = 0;
    // The arrays as local pointers: read through C, B and M (the team's shared references), the
    // compiler must load each array's address again after every store to a force or a contact,
    // which took a tenth of the loop (perf). Local pointers it keeps in registers; the same bits.
    const int* const m1 = C.m1.data();
    const int* const m2 = C.m2.data();
    const int* const b1 = C.b1.data();
    const int* const b2 = C.b2.data();
    const std::uint8_t* const image = C.image.data();
    const Real* const rbar = C.rbar.data();
    Vec3* const normal = C.normal.data();
    Real* const overlap = C.overlap.data();
    Real* const normalForce = C.normalForce.data();
    Vec3* const shearForce = C.shearForce.data();
    Vec3* const rollingMoment = C.rollingMoment.data();
    const Vec3* const memberPos = M.pos.data();
    const Real* const radius = M.radius.data();
    const Vec3* const pos = B.pos.data();
    const Vec3* const vel = B.vel.data();
    const Vec3* const angVel = B.angVel.data();

    // This thread's contacts: whole blocks of kSumBlock pairs, as even a share of them as blocks
    // allow (libgomp's schedule(static) of the blocks), so that the measures summed below are
    // those of the separate pass's blocks. Each thread adds its forces into its own buffer, summed
    // in thread order after the loop: the partition decides the forces' last bits, so it is the
    // same whether or not the step measures.
    int threads = 1;
#ifdef _OPENMP
    threads = omp_get_num_threads();
#endif
    const int share = pairBlocks / threads, extra = pairBlocks % threads;
    const int firstBlock = t < extra ? t * (share + 1) : t * share + extra;
    const int lastBlock = firstBlock + share + (t < extra ? 1 : 0);
    const int lo = std::min(nc, firstBlock * kSumBlock), hi = std::min(nc, lastBlock * kSumBlock);
    // Each thread's pairs in batches of kBatch, in three passes:
    //  1. the distance of every pair, its square root and division two pairs at a time, then the
    //     pairs sorted into touching and not, the touching ones' normal and overlap written
    //     straight into the law's batch;
    //  2. the kinematics of the touching ones (relative velocity, lever arms, spin), then the law
    //     on the whole batch (HertzMindlin::evaluate) and the contact forces and moments, the
    //     arithmetic again two contacts at a time in loops without a choice (SSE2 lanes);
    //  3. the forces stored and added to the bodies, in pair order.
    // Every contact does the arithmetic of a plain one-contact-at-a-time loop, in its order: the same
    // bits as that loop (checked on 1 and 2 threads, rotations free and blocked, rolling resistance, clump1 and
    // clump2 preparations; docs/benchmarks.md, "Two contacts at a time", with what it gained).
    constexpr int kBatch = HertzMindlin::Batch::kSize;
    static_assert(kSumBlock % kBatch == 0, "a batch of pairs lies in one block of the measures' sums");
    static_assert(kBatch % kLanes == 0, "a batch padded to whole lanes fits its arrays");
    // A touching pair's motion, by component like the law's batch: its relative velocity (the
    // bodies' and the affine field's), the spins of its bodies and the lever arms to the contact
    // point. The loops over it that hold no choice run two pairs at a time (see HertzMindlin::Batch).
    struct Motion {
      Real vx[kBatch], vy[kBatch], vz[kBatch];        // relative velocity at the centres; then at the contact
      Real w1x[kBatch], w1y[kBatch], w1z[kBatch];     // angular velocity of body a
      Real w2x[kBatch], w2y[kBatch], w2z[kBatch];     // ... of body b
      Real a1x[kBatch], a1y[kBatch], a1z[kBatch];     // lever arm of body a to the contact point
      Real a2x[kBatch], a2y[kBatch], a2z[kBatch];     // ... of body b
      Real t1x[kBatch], t1y[kBatch], t1z[kBatch];     // out: moment of the contact force about a's centre
      Real t2x[kBatch], t2y[kBatch], t2z[kBatch];     // ... about b's centre
      Real Fx[kBatch], Fy[kBatch], Fz[kBatch];        // out: the contact force on body b
    };
    struct Gap {  // every pair of the batch: the distance vector and what follows from it
      Real dx[kBatch], dy[kBatch], dz[kBatch], rsum[kBatch], dist2[kBatch], overlap[kBatch], inv[kBatch];
    };
    Gap gap;
    // The running sums of the cell measures' terms (measure/CellLanes.hpp) of the block of pairs
    // this thread is in.
    CellLaneSums blockSums;
    int pairOf[kBatch];      // the touching pairs of the batch, in pair order
    Vec3 branches[kBatch];   // their branch vectors
    for (Vec3& L : branches) L.setZero();  // (the measures' last lanes read past a batch's last contact)
    // Zeros at first: the measures' last lanes read past a batch's last contact (and mask it).
    HertzMindlin::Batch q{};
    Motion v{};
    const Real halfDt = 0.5 * dt;
    for (int c0 = lo; c0 < hi; c0 += kBatch) {
      const int c1 = std::min(hi, c0 + kBatch);
      // The distance of every pair: gathered, then its square root and division two pairs at a
      // time (a third of the force loop's time went to them one pair at a time, perf), then the
      // pairs sorted into touching and not.
      const int nk = c1 - c0;
      for (int k = 0; k < nk; ++k) {
        const int c = c0 + k;
        const int i = m1[c], j = m2[c];
        const int a = Clumps ? b1[c] : i, b = Clumps ? b2[c] : j;
        const Vec3& sh = offsets[image[c]];
        const Vec3& pi = Clumps ? memberPos[i] : pos[a];
        const Vec3 pj = (Clumps ? memberPos[j] : pos[b]) + sh;
        const Vec3 d = pj - pi;
        gap.dx[k] = d.x(); gap.dy[k] = d.y(); gap.dz[k] = d.z();
        gap.rsum[k] = radius[i] + radius[j];
        gap.dist2[k] = d.squaredNorm();
      }
      for (int k = 0; k < nk; ++k) {
        const Real dist = std::sqrt(gap.dist2[k]);
        gap.overlap[k] = gap.rsum[k] - dist;
        gap.inv[k] = 1.0 / dist;
      }
      // The pairs sorted into touching and not without a branch: which way a pair goes is a coin
      // toss to the processor (two in three touch), and its mispredictions cost more than the
      // stores to both lists. NaN distances count as touching, as the test dist2 >= rsum^2 had it.
      int touching[kBatch], apart[kBatch];
      int m = 0, gone = 0;
      for (int k = 0; k < nk; ++k) {
        const bool isApart = gap.dist2[k] >= gap.rsum[k] * gap.rsum[k];
        touching[m] = k;
        apart[gone] = k;
        m += !isApart;
        gone += isApart;
      }
      for (int e = 0; e < gone; ++e) {  // not touching: a contact ends and forgets its history
        const int k = apart[e], c = c0 + k;
        if (normalForce[c] != 0) {
          normalForce[c] = 0;
          shearForce[c].setZero();
          if constexpr (Rolling) rollingMoment[c].setZero();
        }
        overlap[c] = gap.overlap[k];
      }
      for (int e = 0; e < m; ++e) {
        // The touching pair's geometry straight into the law's batch: the normal from the
        // distance's scalars (reading back a vector just stored as three scalars as one two-lane
        // load stalls store forwarding, 11 % of the loop by perf), its overlap and its pair.
        const int k = touching[e];
        const Real inv = gap.inv[k];
        q.nx[e] = gap.dx[k] * inv; q.ny[e] = gap.dy[k] * inv; q.nz[e] = gap.dz[k] * inv;
        q.delta[e] = gap.overlap[k];
        pairOf[e] = c0 + k;
        if (!Clumps) branches[e] = Vec3(gap.dx[k], gap.dy[k], gap.dz[k]);  // a clump's: centre to centre, below
      }
      for (int k = 0; k < m; ++k) {
        const int c = pairOf[k];
        const Vec3 n(q.nx[k], q.ny[k], q.nz[k]);
        const Real delta = q.delta[k];
        const int i = m1[c], j = m2[c];
        const int a = Clumps ? b1[c] : i, b = Clumps ? b2[c] : j;
        const Vec3& sh = offsets[image[c]];
        const Real ri = radius[i], rj = radius[j];
        if (Clumps) branches[k] = pos[b] + sh - pos[a];
        const Vec3& branch = branches[k];
        // Velocities are fluctuations: the affine field adds L (x_b - x_a) = L branch.
        const Vec3 vrel = vel[b] - vel[a] + (Sheared ? Vec3(L * branch) : Vec3(rate.cwiseProduct(branch)));
        v.vx[k] = vrel.x(); v.vy[k] = vrel.y(); v.vz[k] = vrel.z();
        if (Rotations) {
          // Lever arms from the body centres to the contact point, mid-overlap as in YADE's
          // ScGeom; the member's image (x + sh) - sh is kept as written, since it is not always x
          // in floating point, and the results' last bits depend on it.
          const Real arm1len = ri - 0.5 * delta, arm2len = rj - 0.5 * delta;
          const Vec3 arm1 = (Clumps ? Vec3(memberPos[i] - pos[a]) : Vec3::Zero()) + arm1len * n;
          const Vec3 arm2 = (Clumps ? Vec3(Vec3(memberPos[j] + sh) - sh - pos[b]) : Vec3::Zero()) - arm2len * n;
          v.a1x[k] = arm1.x(); v.a1y[k] = arm1.y(); v.a1z[k] = arm1.z();
          v.a2x[k] = arm2.x(); v.a2y[k] = arm2.y(); v.a2z[k] = arm2.z();
          const Vec3& w1 = angVel[a];
          const Vec3& w2 = angVel[b];
          v.w1x[k] = w1.x(); v.w1y[k] = w1.y(); v.w1z[k] = w1.z();
          v.w2x[k] = w2.x(); v.w2y[k] = w2.y(); v.w2z[k] = w2.z();
        }
        const Vec3& nPrev = normal[c];
        const Vec3& FsPrev = shearForce[c];
        q.px[k] = nPrev.x(); q.py[k] = nPrev.y(); q.pz[k] = nPrev.z();
        q.fx[k] = FsPrev.x(); q.fy[k] = FsPrev.y(); q.fz[k] = FsPrev.z();
        q.rbar[k] = rbar[c];
        q.loaded[k] = normalForce[c] > 0 ? 1.0 : 0.0;
      }
      // The relative velocity at the contact point, the spin about n and the tangential increment:
      // vrel + w2 x arm2 - w1 x arm1, (dt/2) n.(w1 + w2), (vrel - (n.vrel) n) dt.
      for (int k = 0; k < m; ++k) {
        Real vx = v.vx[k], vy = v.vy[k], vz = v.vz[k];
        const Real nx = q.nx[k], ny = q.ny[k], nz = q.nz[k];
        Real twist = 0;
        if (Rotations) {
          const Real w1x = v.w1x[k], w1y = v.w1y[k], w1z = v.w1z[k];
          const Real w2x = v.w2x[k], w2y = v.w2y[k], w2z = v.w2z[k];
          const Real a1x = v.a1x[k], a1y = v.a1y[k], a1z = v.a1z[k];
          const Real a2x = v.a2x[k], a2y = v.a2y[k], a2z = v.a2z[k];
          vx += (w2y * a2z - w2z * a2y) - (w1y * a1z - w1z * a1y);
          vy += (w2z * a2x - w2x * a2z) - (w1z * a1x - w1x * a1z);
          vz += (w2x * a2y - w2y * a2x) - (w1x * a1y - w1y * a1x);
          twist = halfDt * (nx * (w1x + w2x) + ny * (w1y + w2y) + nz * (w1z + w2z));
        }
        const Real vn = nx * vx + ny * vy + nz * vz;
        q.ux[k] = (vx - vn * nx) * dt;
        q.uy[k] = (vy - vn * ny) * dt;
        q.uz[k] = (vz - vn * nz) * dt;
        q.twist[k] = twist;
      }
      law.evaluate(q, m);
      // The contact force on body b and its moments about the two centres.
      for (int k = 0; k < m; ++k) {
        const Real N = q.N[k];
        const Real Fx = N * q.nx[k] + q.fx[k], Fy = N * q.ny[k] + q.fy[k], Fz = N * q.nz[k] + q.fz[k];
        v.Fx[k] = Fx; v.Fy[k] = Fy; v.Fz[k] = Fz;
        if (Rotations) {
          const Real a1x = v.a1x[k], a1y = v.a1y[k], a1z = v.a1z[k];
          const Real a2x = v.a2x[k], a2y = v.a2y[k], a2z = v.a2z[k];
          v.t1x[k] = a1y * Fz - a1z * Fy; v.t1y[k] = a1z * Fx - a1x * Fz; v.t1z[k] = a1x * Fy - a1y * Fx;
          v.t2x[k] = a2y * Fz - a2z * Fy; v.t2y[k] = a2z * Fx - a2x * Fz; v.t2z[k] = a2x * Fy - a2y * Fx;
        }
      }
      for (int k = 0; k < m; ++k) {
        const int c = pairOf[k];
        const Vec3 n(q.nx[k], q.ny[k], q.nz[k]);
        const Real delta = q.delta[k];
        const int a = Clumps ? b1[c] : m1[c], b = Clumps ? b2[c] : m2[c];
        const Real N = q.N[k];
        if (q.sliding[k] != 0) ++sliding;
        if constexpr (Rolling) {
          // Relative rolling rotation of the step: the spin difference off the normal (the part
          // along n is twist, which this sub-model does not resist).
          const Vec3 dw = (angVel[b] - angVel[a]) * dt;
          const Real ks = law.shearStiffness(HertzMindlin::normalStiffness(N, delta));
          bool capped;
          const Vec3 Mr = law.rollingMoment(rbar[c], N, ks, n, normalForce[c] > 0, normal[c], rollingMoment[c],
                                            dw - n.dot(dw) * n, q.twist[k], capped);
          if (capped) ++rollingCappedHere;
          rollingMoment[c] = Mr;
          T[a] -= Mr;  // the moment on body b, its opposite on body a
          T[b] += Mr;
        }

        normal[c] = n;
        overlap[c] = delta;
        normalForce[c] = N;
        shearForce[c] = Vec3(q.fx[k], q.fy[k], q.fz[k]);
        const Vec3 Fc(v.Fx[k], v.Fy[k], v.Fz[k]);  // force on body b; body a receives -Fc
        F[a] -= Fc;
        F[b] += Fc;
        if (Rotations) {
          T[a] -= Vec3(v.t1x[k], v.t1y[k], v.t1z[k]);
          T[b] += Vec3(v.t2x[k], v.t2y[k], v.t2z[k]);
        }
      }
      if (measure) {
        // The terms of contactMeasures from the values just stored (F = N n + F_s, the branch, n,
        // N and the overlap for k_n), four contacts side by side in vector lanes, each contact's
        // arithmetic that of the separate pass, and added to the running sums of their block
        // contact after contact in pair order (measure/CellLanes.hpp): each sum adds what the
        // separate pass adds, in its order. The lanes past the batch's last contact are masked
        // as no contact (addCellTermsOf).
        int k = 0;
        Lanes Lx, Ly, Lz;
        for (; k + kLanes <= m; k += kLanes) {
          loadVectorLanes(branches[k].data(), Lx, Ly, Lz);
          addCellTerms(loadLanes(v.Fx + k), loadLanes(v.Fy + k), loadLanes(v.Fz + k), Lx, Ly, Lz, loadLanes(q.nx + k),
                       loadLanes(q.ny + k), loadLanes(q.nz + k), loadLanes(q.N + k), loadLanes(q.delta + k), ratio,
                       blockSums);
        }
        if (k < m) {
          loadVectorLanes(branches[k].data(), Lx, Ly, Lz);
          addCellTermsOf(m - k, loadLanes(v.Fx + k), loadLanes(v.Fy + k), loadLanes(v.Fz + k), Lx, Ly, Lz,
                         loadLanes(q.nx + k), loadLanes(q.ny + k), loadLanes(q.nz + k), loadLanes(q.N + k),
                         loadLanes(q.delta + k), ratio, blockSums);
        }
        if (c1 == hi || c1 % kSumBlock == 0) {  // the block's last batch
          pairSums[c0 / kSumBlock] = blockSums.cellSums();
          blockSums = CellLaneSums{};
        }
      }
    }
    // Not a reduction clause: that would change the paper's loop (Rolling false) too.
    if constexpr (Rolling) {
#pragma omp atomic
      rollingAtCap += rollingCappedHere;
    }
    // The threads' buffers into the bodies' arrays, each body's in thread order, in the same team
    // (a second parallel region cost a fork and a join a step); with it the bodies' resultants for
    // the unbalanced force, per block of bodies as its separate pass sums them. The team may be
    // smaller than asked (OMP_DYNAMIC, nesting): only the buffers of threads that ran this step
    // hold this step's forces, so only they are summed.
    int members = 1;
#ifdef _OPENMP
    members = omp_get_num_threads();
#pragma omp barrier
#endif
    if (members > 1 || measure || !Rotations) {
      Vec3* const force = B.force.data();
      Vec3* const torque = B.torque.data();
#pragma omp for schedule(static)
      for (int k = 0; k < bodyBlocks; ++k) {
        const int end = std::min(nb, (k + 1) * kSumBlock);
        Real acc = 0;
        for (int b = k * kSumBlock; b < end; ++b) {
          for (int u = 1; u < members; ++u) {
            force[b] += forceBuffers_[u][b];
            if (Rotations) torque[b] += torqueBuffers_[u][b];
          }
          if (!Rotations) torque[b].setZero();
          if (measure) acc += force[b].norm();
        }
        if (measure) bodySums[k] = acc;
      }
    }
  }
  slidingContacts = sliding;
  rollingCapped = rollingAtCap;
  if (measure) {
    CellSums contacts;
    for (int k = 0; k < pairBlocks; ++k) contacts += pairSums[k];
    Real bodies = 0;
    for (int k = 0; k < bodyBlocks; ++k) bodies += bodySums[k];
    s.measured.contacts = contacts;
    s.measured.bodyForce = bodies;
    s.measured.step = s.step;
  } else {
    s.measured.clear();
  }
}

void ContactForces::apply(Scene& s) {
  require(!s.detectionInvalid, "contact forces need an up-to-date contact list: run ContactDetection first");
  require(s.contacts.image.size() == s.contacts.shift.size(), "contact forces need the detection's image index of each pair");
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
