#include "statics/SparseCholesky.hpp"

#include <cholmod.h>

#include <stdexcept>

namespace trueaniso {

struct SparseCholesky::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  Impl() {
    cholmod_start(&common);
    common.print = 0;             // a non-positive pivot is an expected outcome, not an error to print
    common.error_handler = nullptr;
    common.quick_return_if_not_posdef = 1;  // a failed factorisation is redone after pinning anyway
  }
  ~Impl() {
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  cholmod_sparse view(const Eigen::SparseMatrix<Real>& a) {
    if (!a.isCompressed()) throw std::logic_error("SparseCholesky needs a compressed matrix");
    cholmod_sparse A{};
    A.nrow = A.ncol = static_cast<size_t>(a.rows());
    A.nzmax = static_cast<size_t>(a.nonZeros());
    A.p = const_cast<int*>(a.outerIndexPtr());
    A.i = const_cast<int*>(a.innerIndexPtr());
    A.x = const_cast<Real*>(a.valuePtr());
    A.stype = -1;  // lower triangle stored
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_REAL;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    return A;
  }
};

SparseCholesky::SparseCholesky() : impl_(new Impl) {}
SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::analyze(const Eigen::SparseMatrix<Real>& lower) {
  cholmod_sparse A = impl_->view(lower);
  cholmod_common& c = impl_->common;
  if (impl_->factor) cholmod_free_factor(&impl_->factor, &c);
  // Nested dissection (METIS) only: a contact network is a 3D graph, where METIS always beats
  // minimum degree by far (30% less fill, 2.5x fewer flops on a 4000-sphere packing), and
  // CHOLMOD's default would spend time on an AMD ordering first.
  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_METIS;
  c.postorder = 1;
  impl_->factor = cholmod_analyze(&A, &c);
  if (!impl_->factor) throw std::runtime_error("CHOLMOD could not analyse the stiffness matrix");
}

int SparseCholesky::factorize(const Eigen::SparseMatrix<Real>& lower) {
  if (!impl_->factor) analyze(lower);
  cholmod_sparse A = impl_->view(lower);
  cholmod_common& c = impl_->common;
  cholmod_factorize(&A, impl_->factor, &c);
  if (c.status == CHOLMOD_NOT_POSDEF) {
    const cholmod_factor* L = impl_->factor;
    return static_cast<const int*>(L->Perm)[L->minor];
  }
  if (c.status < CHOLMOD_OK) throw std::runtime_error("CHOLMOD factorisation failed (out of memory?)");
  return -1;
}

Eigen::VectorXd SparseCholesky::pivots() const {
  const cholmod_factor* L = impl_->factor;
  const int n = static_cast<int>(L->n);
  const int* perm = static_cast<const int*>(L->Perm);
  const Real* x = static_cast<const Real*>(L->x);
  Eigen::VectorXd d(n);
  if (L->is_super) {
    const int* super = static_cast<const int*>(L->super);
    const int* pi = static_cast<const int*>(L->pi);
    const int* px = static_cast<const int*>(L->px);
    for (size_t s = 0; s < L->nsuper; ++s) {
      const int nsrow = pi[s + 1] - pi[s];
      for (int k = super[s]; k < super[s + 1]; ++k) {
        const int jj = k - super[s];
        const Real lkk = x[px[s] + jj + static_cast<long>(jj) * nsrow];
        d[perm[k]] = lkk * lkk;
      }
    }
  } else {
    const int* p = static_cast<const int*>(L->p);
    for (int k = 0; k < n; ++k) {
      const Real lkk = x[p[k]];  // the diagonal is first in each column
      d[perm[k]] = L->is_ll ? lkk * lkk : lkk;
    }
  }
  return d;
}

Eigen::MatrixXd SparseCholesky::solve(const Eigen::MatrixXd& rhs) const {
  cholmod_common& c = impl_->common;
  cholmod_dense B{};
  B.nrow = static_cast<size_t>(rhs.rows());
  B.ncol = static_cast<size_t>(rhs.cols());
  B.nzmax = B.nrow * B.ncol;
  B.d = B.nrow;
  B.x = const_cast<Real*>(rhs.data());
  B.xtype = CHOLMOD_REAL;
  B.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* X = cholmod_solve(CHOLMOD_A, impl_->factor, &B, &c);
  if (!X) throw std::runtime_error("CHOLMOD solve failed");
  Eigen::MatrixXd out = Eigen::Map<const Eigen::MatrixXd>(static_cast<const Real*>(X->x), rhs.rows(), rhs.cols());
  cholmod_free_dense(&X, &c);
  return out;
}

long SparseCholesky::factorNonzeros() const { return static_cast<long>(impl_->common.lnz); }
bool SparseCholesky::supernodal() const { return impl_->factor && impl_->factor->is_super; }
double SparseCholesky::flops() const { return impl_->common.fl; }

}  // namespace trueaniso
