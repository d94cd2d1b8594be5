#pragma once
/// @file ltdl.hpp
/// @brief The sparse LᵀDL factorization of the joint-space inertia (Featherstone 2008, §6.5):
/// M = LᵀDL with L unit lower triangular and nonzero only at (i, j), j an ancestor of i — the
/// sparsity the tree induces, so the factor fills no new entries — and M⁻¹x by two triangular
/// sweeps over those entries. This is what MuJoCo's mj_factorM / mj_solveM and Pinocchio's
/// cholesky::decompose / solve compute.
///
/// The solve is O(n·depth) scalar multiply-adds over contiguous memory, against the 6-D
/// transforms that minv_apply carries joint to joint; it pays when one M serves several
/// right-hand sides. At a new point with one right-hand side (FD adjoint's case),
/// minv_apply after aba needs neither M nor its O(n·depth²) factorization.
///
/// Rows are swept as the contiguous index runs of Model::run_start (one run per unbranched
/// stretch of the tree, the whole row on a chain), so that the inner loops run over contiguous
/// memory; a single chain skips the ancestor walk.

#include "idmpc/model/data.hpp"

namespace idmpc {

namespace detail {

/// @brief Calls f(first, count) for each run of consecutive links among the ancestors of i,
/// nearest run first; together they are exactly the ancestors of i. `chain`: the model is one
/// chain (model.run_start[n − 1] == 0), whose ancestors of i are the one run 0 … i − 1, taken
/// without walking the parents.
template <typename F> void for_ancestor_runs(const Model& model, bool chain, int i, F&& f) {
  if (chain) {
    f(0, i);
    return;
  }
  for (int j = model.parent[i]; j >= 0;) {
    const int r = model.run_start[j];
    f(r, j - r + 1);
    j = model.parent[r];
  }
}

}  // namespace detail

/// @brief Factors data.M = LᵀDL in place of data.Lt (column k: L(k, j) at the ancestors j of
/// k, unit diagonal implied) and data.Dl, data.Dlinv = 1/D; O(Σ depth²) multiply-adds.
/// Precondition: data.M holds M(q), from crba or rnea_derivatives (checked in debug builds).
template <typename S> void ltdl_factor(const Model& model, DataTpl<S>& data) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n, "ltdl_factor: data was made for a model of another size");
  IDMPC_CHECK_ARGUMENT(data.parts.has(DataParts::ltdl()), "ltdl_factor: data was made without its ltdl part");
  IDMPC_DEBUG_CHECK(data.passes.holds_mass_matrix(),
                    "ltdl_factor needs data.M: call crba or rnea_derivatives first");
  const int n = model.n;
  const bool chain = model.run_start[n - 1] == 0;
  auto& Lt = data.Lt;
  // the lower triangle of M at the ancestor entries, row k into column k (M is symmetric)
  for (int k = 0; k < n; ++k) {
    data.Dl[k] = data.M(k, k);
    const S* const mk = data.M.col(k).data();
    S* const lk = Lt.col(k).data();
    detail::for_ancestor_runs(model, chain, k, [&](int r, int len) {
      for (int t = r; t < r + len; ++t) lk[t] = mk[t];
    });
  }
  // leaves first: row k is complete when k is reached; eliminate it from its ancestors' rows.
  // H(i, j) −= H(k, i)·H(k, j)/H(k, k) for j = i and the ancestors of i (all ancestors of k,
  // not yet scaled: i goes up from k's parent), then H(k, i) ← H(k, i)/H(k, k)
  for (int k = n - 1; k >= 0; --k) {
    const S dk_inv = S(1) / data.Dl[k];
    data.Dlinv[k] = dk_inv;
    S* const lk = Lt.col(k).data();
    for (int i = model.parent[k]; i >= 0; i = model.parent[i]) {
      const S hki = lk[i];
      const S a = hki * dk_inv;
      data.Dl[i] -= a * hki;
      S* const li = Lt.col(i).data();
      detail::for_ancestor_runs(model, chain, i, [&](int r, int len) {
        for (int t = r; t < r + len; ++t) li[t] -= a * lk[t];
      });
      lk[i] = a;
    }
  }
  data.passes.ltdl();
}

/// @brief y = M⁻¹x with the factor of the last ltdl_factor call: z = L⁻ᵀx leaves first, then
/// y = L⁻¹D⁻¹z root first. Returns data.y_ltdl. Precondition: ltdl_factor was called on data
/// (checked in debug builds); later passes of other algorithms do not touch the factor.
template <typename S, typename Xx>
const VecX<S>& ltdl_solve(const Model& model, DataTpl<S>& data, const Eigen::MatrixBase<Xx>& x) {
  IDMPC_CHECK_ARGUMENT(data.n == model.n && x.size() == model.n, "ltdl_solve: x must have size model.n");
  IDMPC_DEBUG_CHECK(data.passes.holds_ltdl(), "ltdl_solve needs ltdl_factor(model, data) first");
  const int n = model.n;
  const bool chain = model.run_start[n - 1] == 0;
  auto& y = data.y_ltdl;
  S* const yp = y.data();
  for (int k = 0; k < n; ++k) yp[k] = x[k];
  const S* const L = data.Lt.data();  // column k at L + k·n
  // Lᵀz = x: z_k is final once the rows below it are done; it enters its ancestors' rows
  for (int k = n - 1; k > 0; --k) {
    const S zk = yp[k];
    const S* const lk = L + static_cast<Eigen::Index>(k) * n;
    detail::for_ancestor_runs(model, chain, k, [&](int r, int len) {
      for (int t = r; t < r + len; ++t) yp[t] -= zk * lk[t];
    });
  }
  // L y = D⁻¹z: y_k takes the ancestors' results, which are final
  for (int k = 0; k < n; ++k) {
    const S* const lk = L + static_cast<Eigen::Index>(k) * n;
    S yk = yp[k] * data.Dlinv[k];
    detail::for_ancestor_runs(model, chain, k, [&](int r, int len) {
      for (int t = r; t < r + len; ++t) yk -= lk[t] * yp[t];
    });
    yp[k] = yk;
  }
  return y;
}

}  // namespace idmpc
