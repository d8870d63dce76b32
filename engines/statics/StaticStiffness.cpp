#include "statics/StaticStiffness.hpp"

#include <Eigen/LU>
#include <chrono>
#include <limits>

#include "measure/Stress.hpp"
#include "statics/HeldState.hpp"
#include "statics/NetworkMatrix.hpp"
#include "statics/Rattlers.hpp"
#include "statics/PreconditionedSolve.hpp"
#include "statics/SparseCholesky.hpp"

namespace trueaniso {

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// Per strain: ||f|| if the affine field leaves the bodies out of balance, else the contacts' own
// affine force increments (the scale any residual is measured against).
Vec6 residualScale(const Eigen::MatrixXd& f, const Vec6& contactLoad) {
  Vec6 s;
  for (int J = 0; J < 6; ++J) {
    const Real fn = f.col(J).norm();
    s[J] = fn > 1e-9 * contactLoad[J] ? fn : contactLoad[J];
  }
  return s;
}

Real relativeResidual(const Eigen::MatrixXd& r, const Vec6& scale) {  // as PreconditionedSolve's
  Real worst = 0;
  for (int J = 0; J < 6; ++J) worst = std::max(worst, r.col(J).norm() / scale[J]);
  return worst;
}

}  // namespace

StaticStiffnessResult StaticStiffness::compute(const Scene& scene) const {
  // The network matrix has no rolling springs (k_r on the relative rotations): refused rather than
  // answered for another contact law (docs/rolling.md).
  require(!scene.material.rolling(), "the static solve does not model rolling resistance: set the rolling "
                                     "stiffness factor to 0, or measure the stiffness with stress probes");
  const auto t0 = Clock::now();
  StaticStiffnessResult res;
  res.rotations = rotations;
  const Scene held = heldState(scene);
  requireBalance(held, maxUnbalanced, rotations);
  const Balance bal = balance(held);
  res.unbalancedForce = bal.forces;
  res.unbalancedTorque = bal.torques;
  const std::vector<char> rattler = findRattlers(held);
  for (int b = 0; b < held.bodies.size(); ++b)
    if (rattler[b]) res.rattlers.push_back(b);
  require(static_cast<int>(res.rattlers.size()) < held.bodies.size(),
          "no body carries load (every body is a rattler): there is no contact network to stiffen");
  res.volume = held.cell.volume();
  res.stress = loveWeberStress(held);
  const Vec6 sigma = voigt::fromTensor(res.stress);
  Mat6 volumeTerm = Mat6::Zero();  // d sigma/de gets -sigma tr(E): C gets +sigma m^T
  for (int J = 0; J < 3; ++J) volumeTerm.col(J) = sigma;
  const auto t1 = Clock::now();

  NetworkMatrix net = assembleNetwork(held, rattler, rotations);
  const Real V = res.volume;
  res.affineNormal = -net.SEnormalAll / V;
  res.affineShear = -net.SEshearAll / V;
  res.affineGeometric = -net.SEgeometricAll / V + volumeTerm;
  res.affine = res.affineNormal + res.affineShear + res.affineGeometric;
  res.bodies = static_cast<int>(net.bodyOfBlock.size());
  res.dofs = net.size();
  res.contacts = net.contacts;

  std::vector<char> pinned(net.size(), 0);
  // Local modes first: the global translation is then pinned on a body whose DOFs were not turned.
  const std::vector<PinnedDof> local = rotateLocalModes(net, zeroModeTolerance, softModeTolerance);
  for (const std::vector<PinnedDof>& group : {pinGlobalTranslation(net), local})
    for (const PinnedDof& p : group) {
      pinned[p.dof] = 1;
      res.pinned.push_back(p);
    }
  const auto t2 = Clock::now();

  SparseCholesky chol;
  chol.analyze(pinnedSymmetricLower(net.K, pinned));
  const auto t2a = Clock::now();
  for (const PinnedDof& p : factorizeWithPins(chol, net, pinned, pivotTolerance, softModeTolerance, maxFactorizations,
                                                   &res.factorizations))
    res.pinned.push_back(p);
  res.factorNonzeros = chol.factorNonzeros();
  res.factorFlops = chol.flops();
  res.supernodal = chol.supernodal();
  const auto t3 = Clock::now();

  // K u = f for the six unit strains, on the pinned system (PreconditionedSolve.hpp).
  Eigen::MatrixXd f = net.JE;
  for (int d = 0; d < net.size(); ++d)
    if (pinned[d]) f.row(d).setZero();
  const Vec6 scale = residualScale(net.JE, net.contactLoadNorm);
  SolveReport rep;
  const Eigen::MatrixXd u = preconditionedSolve(pinnedCopy(net.K, pinned), chol, f, scale, tolerance, maxIterations,
                                                &rep, forceGmres);
  res.iterations = rep.refinements;
  res.gmresIterations = rep.gmresIterations;
  // Residual of the full system, split into the equations solved and those of pinned DOFs.
  Eigen::MatrixXd full = net.JE - net.K * u, reaction = Eigen::MatrixXd::Zero(full.rows(), 6);
  for (int d = 0; d < net.size(); ++d)
    if (pinned[d]) { reaction.row(d) = full.row(d); full.row(d).setZero(); }
  res.residual = relativeResidual(full, scale);
  res.pinnedReaction = relativeResidual(reaction, scale);

  const Mat6 dSigmaV = net.SE + net.S * u;
  res.C = -dSigmaV / V + volumeTerm;
  Eigen::FullPivLU<Mat6> lu(res.C);
  res.compliance = lu.isInvertible() ? Mat6(lu.inverse()) : Mat6::Constant(std::numeric_limits<Real>::quiet_NaN());
  res.constants = orthotropicModuli(res.C);
  const auto t4 = Clock::now();
  res.timeHeld = seconds(t0, t1);
  res.timeAssembly = seconds(t1, t2);
  res.timeAnalysis = seconds(t2, t2a);
  res.timeFactorization = seconds(t2a, t3);
  res.timeSolve = seconds(t3, t4);
  res.timeTotal = seconds(t0, t4);
  return res;
}

}  // namespace trueaniso
