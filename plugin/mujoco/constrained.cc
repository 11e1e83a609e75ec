// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// constraints = 1: the drives solved with MuJoCo's constraint solve in the loop (README.md,
// "Constraints"). The exact coupled solve predicts the end-of-step velocity without constraint
// forces; contacts, joint limits, equalities and friction loss then move the joints, and a drive
// inside its envelope at the predicted velocity can end the step outside it. Here, inside the
// plugin's compute (mj_fwdActuation: efc_* and their velocities are already built), each candidate
// set of efforts is run through MuJoCo's own mj_fwdConstraint and the integrator's velocity update,
// and the drives are re-solved against the velocities that gives. A plain fixed point on those
// velocities does not converge (a released drive flips between 0 and its cap), so each re-solve
// is a Newton step: the coupled solve (Newton and Gauss-Seidel, solve.cc) on the drives' linear
// response through the constrained Hessian M + h*D' + J'*D*J of the rows MuJoCo's solve left
// active. The loop stops at the first set of efforts that MuJoCo's solve shows inside every
// envelope (or letting go), or after kMaxConstrained re-solves with the best set it checked.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <mujoco/mujoco.h>

#include "coupled.h"

namespace drive_envelope::mujoco_plugin {
namespace {

// re-solves per step at most; each costs one constraint solve more (the first check is one too)
constexpr int kMaxConstrained = 4;

// inside: no envelope margin below -kCheckTolerance of its cap at MuJoCo's end-of-step velocity;
// above MuJoCo's solver noise (its Newton solve stops at opt.tolerance), below the 1e-6 with
// which `drive-envelope check` counts a sample outside
constexpr double kCheckTolerance = 1e-8;

}  // namespace

void CoupledSolver::ConstrainedVelocity(const mjModel* m, mjData* d, double dt) {
  // the candidate efforts through MuJoCo's own acceleration and constraint stages, then the
  // velocity update of Euler / implicitfast: (M + h*D') a = qfrc_smooth + qfrc_constraint
  int nv = m->nv;
  mju_copy(d->qfrc_smooth, smooth_.data(), nv);
  for (size_t k = 0; k < drives_.size(); k++) {
    if (request_[k].active) d->qfrc_smooth[drives_[k].dof] += effort_[k];
  }
  mj_solveM(m, d, d->qacc_smooth, d->qfrc_smooth, 1);
  mj_fwdConstraint(m, d);
  constraint_solves_++;

  mjtNum* f = cfactor_.data();
  mjtNum* a = cacc_.data();
  mju_copy(f, d->M, m->nC);
  for (int r = 0; r < nrow_; r++) {
    int dof = rows_[r].dof;
    f[m->M_rowadr[dof] + m->M_rownnz[dof] - 1] += dt * damp0_[r];
  }
  for (int i = 0; i < nv; i++) a[i] = d->qfrc_smooth[i] + d->qfrc_constraint[i];
  bool factored = true;
  for (int k = nv - 1; k >= 0 && factored; k--) {  // f = L'*D*L in place, as mj_factorI
    int start = m->M_rowadr[k], diag = m->M_rownnz[k] - 1, end = start + diag;
    factored = f[end] > mjMINVAL && std::isfinite(f[end]);
    double inverse = factored ? 1 / f[end] : 0;
    cdinv_[k] = inverse;
    for (int adr = end - 1; adr >= start; adr--) {
      int i = m->M_colind[adr];
      double scale = -f[adr] * inverse;
      for (int j = 0, row = m->M_rowadr[i]; j < m->M_rownnz[i]; j++) f[row + j] += f[start + j] * scale;
    }
    for (int adr = start; adr < end; adr++) f[adr] *= inverse;
  }
  if (factored) {
    for (int k = nv - 1; k > 0; k--) {
      double ak = a[k];
      if (ak == 0) continue;
      for (int adr = m->M_rowadr[k]; adr < m->M_rowadr[k] + m->M_rownnz[k] - 1; adr++) {
        a[m->M_colind[adr]] -= f[adr] * ak;
      }
    }
    for (int k = 0; k < nv; k++) a[k] *= cdinv_[k];
    for (int k = 0; k < nv; k++) {
      double sum = 0;
      for (int adr = m->M_rowadr[k]; adr < m->M_rowadr[k] + m->M_rownnz[k] - 1; adr++) {
        sum += f[adr] * a[m->M_colind[adr]];
      }
      a[k] -= sum;
    }
  } else {
    mju_copy(a, d->qacc, nv);  // a singular M + h*D': MuJoCo's own acceleration
  }
  for (int r = 0; r < nrow_; r++) cv_[r] = qvel_[r] + dt * a[rows_[r].dof];
}

double CoupledSolver::Violation(double dt) const {
  // the largest relative margin below 0 of any drive at MuJoCo's end-of-step velocity; a drive
  // giving 0 counts as inside (0 is inside, or the release above its no-load speed)
  double worst = 0;
  for (int r = 0; r < nrow_; r++) {
    int k = rows_[r].drive;
    if (k < 0 || !request_[k].active || effort_[k] == 0) continue;
    const DriveParams& p = request_[k].params;
    double tau = std::fabs(effort_[k]), v = std::fabs(cv_[r]);
    if (!std::isfinite(v)) return std::numeric_limits<double>::infinity();
    if (std::isfinite(p.max_effort) && p.max_effort > 0) {
      double margin = p.max_effort - p.velocity_dependent_resistance * v - tau;
      worst = std::fmax(worst, -margin / p.max_effort);
    }
    if (std::isfinite(p.max_actuator_velocity) && p.max_actuator_velocity > 0) {
      double margin = p.max_actuator_velocity - p.speed_effort_gradient * tau - v;
      worst = std::fmax(worst, -margin / p.max_actuator_velocity);
    }
  }
  return worst;
}

bool CoupledSolver::ConstrainedResponse(const mjModel* m, mjData* d, double dt) {
  // the rows' response A_c = (M + h*D' + J'*D*J)^-1 over the constraint rows MuJoCo's solve left
  // in the quadratic zone (mj_constraintUpdate at its qacc: efc_state; elliptic cones in their
  // middle zone taken as quadratic, an approximation that only slows Newton down: each step is
  // checked by MuJoCo's solve itself), dense: the drives are tens, not thousands
  int nv = m->nv, nefc = d->nefc, n = nrow_;
  if (static_cast<int>(jar_.size()) < nefc) jar_.resize(nefc);
  mj_mulJacVec(m, d, jar_.data(), d->qacc);
  for (int i = 0; i < nefc; i++) jar_[i] -= d->efc_aref[i];
  mjtNum cost = 0;
  mj_constraintUpdate(m, d, jar_.data(), &cost, 0);

  mjtNum* h = hess_.data();
  mj_fullM(m, d, h);
  for (int r = 0; r < n; r++) h[rows_[r].dof * (nv + 1)] += dt * damp0_[r];
  bool sparse = mj_isSparse(m);
  for (int i = 0; i < nefc; i++) {
    int state = d->efc_state[i];
    if (state != mjCNSTRSTATE_QUADRATIC && state != mjCNSTRSTATE_CONE) continue;
    double weight = d->efc_D[i];
    int nnz = sparse ? d->efc_J_rownnz[i] : nv;
    const mjtNum* j = d->efc_J + (sparse ? d->efc_J_rowadr[i] : i * nv);
    const int* col = sparse ? d->efc_J_colind + d->efc_J_rowadr[i] : nullptr;
    for (int a = 0; a < nnz; a++) {
      double wa = weight * j[a];
      if (wa == 0) continue;
      mjtNum* hrow = h + (sparse ? col[a] : a) * nv;
      for (int b = 0; b < nnz; b++) hrow[sparse ? col[b] : b] += wa * j[b];
    }
  }
  if (mju_cholFactor(h, nv, mjMINVAL) < nv) return false;
  for (int r = 0; r < n; r++) {
    for (int i = 0; i < nv; i++) unit_[i] = 0;
    unit_[rows_[r].dof] = 1;
    mju_cholSolve(col_.data(), h, unit_.data(), nv);
    for (int s = 0; s < n; s++) a_[r * n + s] = col_[rows_[s].dof];
  }
  for (int r = 0; r < n; r++) {  // symmetric up to rounding: the sweeps read rows as columns
    for (int s = r + 1; s < n; s++) {
      double mean = 0.5 * (a_[r * n + s] + a_[s * n + r]);
      a_[r * n + s] = a_[s * n + r] = mean;
    }
    if (!(a_[r * n + r] > 0) || !std::isfinite(a_[r * n + r])) return false;
  }
  return true;
}

int CoupledSolver::Constrained(const mjModel* m, mjData* d, double dt) {
  int nv = m->nv, n = nrow_;
  bool sleeping = (m->opt.enableflags & mjENBL_SLEEP) && d->nv_awake < nv;
  // RK4 evaluates the actuators at four stages of one step (no one end-of-step velocity);
  // MuJoCo's implicit effective metric (flex) and sleeping islands change what the solve sees
  if (d->nefc == 0 || (m->opt.disableflags & mjDSBL_CONSTRAINT) || m->opt.integrator == mjINT_RK4 ||
      d->efm_active || sleeping) {
    return 0;
  }
  if (static_cast<int>(cv_.size()) != n) {  // first use: the buffers of this mjData
    warm_.assign(nv, 0);
    cacc_.assign(nv, 0);
    cfactor_.assign(m->nC, 0);
    cdinv_.assign(nv, 0);
    hess_.assign(nv * nv, 0);
    unit_.assign(nv, 0);
    col_.assign(nv, 0);
    cv_.assign(n, 0);
    damp0_.assign(n, 0);
    best_effort_.assign(drives_.size(), 0);
  }
  damp0_ = damp_;
  mju_copy(warm_.data(), d->qacc_warmstart, nv);

  double best = std::numeric_limits<double>::infinity();
  int steps = 0;  // outer re-solves plus the inner Newton steps and sweeps they took
  for (int outer = 0;; outer++) {
    ConstrainedVelocity(m, d, dt);
    double violation = Violation(dt);
    if (violation < best) {
      best = violation;
      best_effort_ = effort_;
    }
    if (!(violation > kCheckTolerance) || outer == kMaxConstrained) break;
    if (!ConstrainedResponse(m, d, dt)) break;
    steps++;

    // linearised at the checked efforts: v1 = cv + A_c (x - x_checked); the damping is inside
    // A_c, so the rows carry none of their own, and every drive starts from its checked impulse
    full_ = response_ = true;
    tree_ = false;  // A_c is not M's inverse: the Newton steps take the dense block
    for (int r = 0; r < n; r++) {
      int k = rows_[r].drive;
      bool drive = k >= 0 && request_[k].active;
      x_[r] = drive ? effort_[k] * dt : 0;
      y_[r] = 0;
      damp_[r] = 0;
      adiag_[r] = a_[r * n + r];
      released_[r] = -1;
      flips_[r] = 0;
    }
    for (int r = 0; r < n; r++) {
      double v = cv_[r];
      for (int s = 0; s < n; s++) v -= a_[r * n + s] * x_[s];
      vfree_[r] = v;
    }
    Prepare(d, dt);
    Velocities();
    steps += Settle(m, d, dt);
    mju_copy(d->qacc_warmstart, d->qacc, nv);  // the next check starts from this solve's answer
  }
  effort_ = best_effort_;
  damp_ = damp0_;
  mju_copy(d->qacc_warmstart, warm_.data(), nv);  // MuJoCo's own solve after actuation starts as it would
  return steps;
}

}  // namespace drive_envelope::mujoco_plugin
