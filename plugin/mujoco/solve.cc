// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// The coupled solve proper: the linear solve of the unclamped laws (sparse, on M's tree), Newton
// steps on the drives' own solves, Gauss-Seidel sweeps (see coupled.h and README.md, "Control law").

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

#include "coupled.h"

namespace drive_envelope::mujoco_plugin {
namespace {

// whether a total impulse x and the end-of-step velocity v it gives lie inside the envelope by a
// relative margin of 1e-9: then ClampDriveImpulse would return the request x unchanged
bool Inside(const DriveParams& p, double dt, double x, double v) {
  constexpr double kMargin = 1e-9;
  double ax = std::fabs(x), av = std::fabs(v), xmax = p.max_effort * dt;
  double vmax = p.max_actuator_velocity;
  bool effort_ok = std::isinf(xmax) ||
                   xmax - p.velocity_dependent_resistance * dt * av - ax > kMargin * xmax;
  bool speed_ok = std::isinf(vmax) || vmax - p.speed_effort_gradient / dt * ax - av > kMargin * vmax;
  return effort_ok && speed_ok;
}

// solves a*x = b in place (b becomes x) for a general n x n row-major a, by Gaussian elimination
// with partial pivoting; false if a is singular. Hand-written because the Newton system
// (I - diag(slope)*A_off) is not symmetric where a slope is positive (SymmetricSolve takes every
// other case) and MuJoCo's public API (mujoco.h, 4.0) factors only symmetric positive definite
// matrices (mju_cholFactor: SymmetricSolve, and the SPD block in constrained.cc)
bool LuSolve(double* a, double* b, int n) {
  for (int k = 0; k < n; k++) {
    int best = k;
    for (int i = k + 1; i < n; i++) {
      if (std::fabs(a[i * n + k]) > std::fabs(a[best * n + k])) best = i;
    }
    if (!(std::fabs(a[best * n + k]) > mjMINVAL)) return false;
    if (best != k) {
      for (int j = 0; j < n; j++) std::swap(a[k * n + j], a[best * n + j]);
      std::swap(b[k], b[best]);
    }
    double inverse = 1 / a[k * n + k];
    for (int i = k + 1; i < n; i++) {
      double factor = a[i * n + k] * inverse;
      if (factor == 0) continue;
      for (int j = k + 1; j < n; j++) a[i * n + j] -= factor * a[k * n + j];
      b[i] -= factor * b[k];
    }
  }
  for (int i = n - 1; i >= 0; i--) {
    for (int j = i + 1; j < n; j++) b[i] -= a[i * n + j] * b[j];
    b[i] /= a[i * n + i];
  }
  return true;
}

// the Newton system (I - diag(slope)*A_off) w = rhs as a symmetric one, where no slope is
// positive: a row with slope 0 reads w_r = rhs_r; dividing row r by t_r = -slope_r > 0 gives
// H w = b with H = diag(1/t) + A_off, symmetric as A is, and positive definite in the common case
// (an unclamped row has 1/t_r = A_rr + 1/alpha_r). MuJoCo's Cholesky then does half of LuSolve's
// work. False (rhs untouched; the caller runs LuSolve) where a slope is positive or not finite,
// or H is not positive definite
bool SymmetricSolve(const double* a, const double* slope, double* rhs, int n, std::vector<int>* rows,
                    std::vector<mjtNum>* h, std::vector<mjtNum>* b) {
  rows->clear();
  for (int r = 0; r < n; r++) {
    if (!(slope[r] <= 0)) return false;
    if (slope[r] < 0) rows->push_back(r);
  }
  int count = static_cast<int>(rows->size());
  h->resize(static_cast<size_t>(count) * count);
  b->resize(count);
  for (int i = 0; i < count; i++) {
    int r = (*rows)[i];
    double t = -slope[r];
    double known = 0;  // the rows with slope 0 are fixed: their terms move to the right side
    for (int s = 0; s < n; s++) {
      if (s != r && slope[s] == 0) known += a[r * n + s] * rhs[s];
    }
    (*b)[i] = rhs[r] / t - known;
    for (int j = 0; j < count; j++) (*h)[i * count + j] = i == j ? 1 / t : a[r * n + (*rows)[j]];
  }
  if (count > 0) {
    if (mju_cholFactor(h->data(), count, mjMINVAL) < count) return false;
    mju_cholSolve(b->data(), h->data(), b->data(), count);
  }
  for (int i = 0; i < count; i++) rhs[(*rows)[i]] = (*b)[i];
  return true;
}

}  // namespace

void CoupledSolver::Prepare(const mjData* d, double dt) {
  // each row's unclamped law is linear in its end-of-step velocity: w = c - alpha*v1, with w the
  // row's total impulse (drive x plus implicit damping y); the clamp only ever shrinks x
  int n = nrow_;
  for (int r = 0; r < n; r++) {
    double hd = dt * damp_[r];
    double response = adiag_[r];
    double reff = response / (1 + response * hd);
    double c = hd * qvel_[r], alpha = hd;
    int k = rows_[r].drive;
    if (k >= 0 && request_[k].active) {
      const Request& q = request_[k];
      const DriveParams& p = q.params;
      double a = dt * (dt * p.stiffness + p.damping);
      double b = dt * p.stiffness * (q.target_pos - d->qpos[drives_[k].qpos]) +
                 dt * p.damping * q.target_vel;
      c += q.ff * dt;
      if (drives_[k].drive_type == DriveType::kAcceleration) {
        c += b / reff;  // J = (b - a*v1)/r: gains per unit inertia
        alpha += a / reff;
      } else if (reff > 0) {
        c += b;  // J = b - a*v1: the spring-damper law at the end-of-step velocity
        alpha += a;
      }
    }
    lin_c_[r] = c;
    lin_alpha_[r] = alpha;
  }
}

void CoupledSolver::LinearGuess(const mjModel* m, const mjData* d) {
  // the solve's starting point: every row's unclamped law w = c - alpha*v1 at once. With
  // v1 = vfree + M^-1 P' w that is (M + P' diag(alpha) P) dv = P' (c - alpha*vfree), v1 = vfree + dv
  // at the rows: M's own sparsity (the tree), factored as MuJoCo factors M (mj_factorI), so no
  // block of M^-1 is needed. Newton and the sweeps then clamp and correct it, so a failed
  // factorization only costs iterations: it falls back to one Jacobi step from vfree. The loop is
  // mj_factorI's own because mujoco.h (4.0) has no call that factors a matrix other than d->M:
  // mj_factorM writes d->qLD, which the constraint solver reads after the drives
  int n = nrow_, nv = m->nv;
  mjtNum* h = h_.data();
  mjtNum* x = delta_.data();
  for (int i = 0; i < m->nC; i++) h[i] = d->M[i];
  for (int i = 0; i < nv; i++) x[i] = 0;
  for (int r = 0; r < n; r++) {
    int dof = rows_[r].dof;
    h[m->M_rowadr[dof] + m->M_rownnz[dof] - 1] += lin_alpha_[r];
    x[dof] = lin_c_[r] - lin_alpha_[r] * vfree_[r];
  }
  bool factored = true;
  for (int k = nv - 1; k >= 0 && factored; k--) {  // h = L'*D*L in place, D^-1 apart
    int start = m->M_rowadr[k], diag = m->M_rownnz[k] - 1, end = start + diag;
    factored = h[end] > mjMINVAL && std::isfinite(h[end]);
    double inverse = factored ? 1 / h[end] : 0;
    hdinv_[k] = inverse;
    for (int adr = end - 1; adr >= start; adr--) {
      int i = m->M_colind[adr];
      double scale = -h[adr] * inverse;
      for (int j = 0, row = m->M_rowadr[i]; j < m->M_rownnz[i]; j++) h[row + j] += h[start + j] * scale;
    }
    for (int adr = start; adr < end; adr++) h[adr] *= inverse;
  }
  if (factored) {
    for (int k = nv - 1; k > 0; k--) {  // L'^-1
      double xk = x[k];
      if (xk == 0) continue;
      for (int adr = m->M_rowadr[k]; adr < m->M_rowadr[k] + m->M_rownnz[k] - 1; adr++) {
        x[m->M_colind[adr]] -= h[adr] * xk;
      }
    }
    for (int k = 0; k < nv; k++) x[k] *= hdinv_[k];  // D^-1
    for (int k = 0; k < nv; k++) {  // L^-1
      double sum = 0;
      for (int adr = m->M_rowadr[k]; adr < m->M_rowadr[k] + m->M_rownnz[k] - 1; adr++) {
        sum += h[adr] * x[m->M_colind[adr]];
      }
      x[k] -= sum;
    }
  }
  for (int r = 0; r < n; r++) {
    double v1 = vfree_[r] + (factored ? x[rows_[r].dof] : 0);
    w_[r] = lin_c_[r] - lin_alpha_[r] * v1;
    v_[r] = v1;
    if (!std::isfinite(w_[r]) || !std::isfinite(v1)) {
      w_[r] = 0;
      v_[r] = vfree_[r];  // a row set to 0 no longer moves the others: they are recomputed below
      factored = false;
    }
  }
  if (!factored) {
    for (int r = 0; r < n; r++) {
      w_[r] = std::isfinite(w_[r]) ? w_[r] : 0;
    }
    FullResponse(d);
    for (int r = 0; r < n; r++) x_[r] = w_[r], y_[r] = 0;
    Velocities();
  }
}

CoupledSolver::RowResult CoupledSolver::RowSolve(int r, double rest, double dt, const mjData* d) {
  solves_++;
  double response = a_[r * nrow_ + r];

  // implicit joint damping y = -h*D'*(v1 - qvel) folded in: v1 = base + reff*x, linear in x
  double hd = dt * damp_[r];
  double scale = 1 / (1 + response * hd);
  double reff = response * scale;
  double base = (rest + response * hd * qvel_[r]) * scale;

  RowResult out;
  int k = rows_[r].drive;
  if (k >= 0 && request_[k].active && flips_[r] < kMaxFlips) {
    const Request& q = request_[k];
    const DriveParams& p = q.params;
    const Drive& drive = drives_[k];

    // implicit PD impulse at the velocity with the feed-forward applied, then the envelope clamp
    // on the TOTAL actuator impulse (drive + ff), evaluated at the end-of-step velocity
    double ff = q.ff * dt;
    double v0 = base + reff * ff;
    double error = q.target_pos - d->qpos[drive.qpos];
    double request = ff + dt * ImplicitDriveEffort(p.stiffness, p.damping, error, v0, q.target_vel,
                                                   reff, dt, drive.drive_type);
    double x = ClampDriveImpulse<double>(v0, ff, request, reff, p.max_actuator_velocity,
                                         p.max_effort * dt, p.speed_effort_gradient / dt,
                                         p.velocity_dependent_resistance * dt);

    // NaN or overflowing states: the drive lets go instead of writing NaN; and (x*dt)/dt can
    // round one ulp above the request: the clamp never grows a request, nor may we
    double effort = std::isfinite(x) ? x / dt : 0;
    double limit = std::fabs(request / dt);
    effort = std::fabs(effort) < limit ? effort : std::copysign(limit, effort);
    out.effort = std::isfinite(effort) ? effort : 0;
    out.x = std::isfinite(x) ? x : 0;
    out.clamped = out.x != request;
  }
  out.y = -hd * (base + reff * out.x - qvel_[r]);
  if (!std::isfinite(out.y)) out.y = 0;
  return out;
}

void CoupledSolver::Track(int r, const RowResult& result) {
  // letting go (0) is the one jump of the clamp: a drive that the others push back and forth
  // across it could cycle forever, so after kMaxFlips it stays let go for the rest of the step
  // (0 is always consistent: inside the envelope, or released above its no-load speed)
  int k = rows_[r].drive;
  if (k < 0 || !request_[k].active) return;
  int zero = result.x == 0;
  if (released_[r] >= 0 && zero != released_[r]) flips_[r]++;
  released_[r] = zero;
  effort_[k] = result.effort;
}

void CoupledSolver::Velocities() {
  // v = vfree + A*(x + y), column by column (independent updates)
  int n = nrow_;
  for (int r = 0; r < n; r++) v_[r] = vfree_[r];
  for (int s = 0; s < n; s++) {
    double ws = x_[s] + y_[s];
    if (ws == 0) continue;
    const double* column = a_.data() + s * n;  // A is symmetric: row s is column s
    for (int r = 0; r < n; r++) v_[r] += column[r] * ws;
  }
}

bool CoupledSolver::Newton(const mjData* d, double dt, int* iterations) {
  // Newton's method on the fixed point w_r = G_r(rest_r(w)), where G_r is a row's own solve
  // (PD, clamp, damping) as a function of the velocity the other rows give it,
  // rest_r = vfree_r + sum_{s != r} A_rs w_s. G_r is piecewise linear: its slope is
  // -alpha/(1 + alpha*A_rr) where the clamp did not bind, else measured (the clamp is only ever
  // evaluated, never rewritten). Each step solves (I - diag(slope)*A_off) w = G - slope*(rest - vfree)
  int n = nrow_;
  for (int it = 0; it < kMaxNewton; it++) {
    double residual = 0;
    for (int r = 0; r < n; r++) {
      double response = a_[r * n + r];
      double held = x_[r] + y_[r];
      rest_[r] = v_[r] - response * held;
      result_[r] = RowSolve(r, rest_[r], dt, d);
      Track(r, result_[r]);
      double g = result_[r].x + result_[r].y;
      residual = std::fmax(residual, std::fabs(g - held) * response / (1 + std::fabs(v_[r])));
    }
    *iterations = it + 1;
    if (!(residual > kTolerance)) {
      for (int r = 0; r < n; r++) {
        x_[r] = result_[r].x;
        y_[r] = result_[r].y;
      }
      Velocities();
      return true;
    }
    for (int r = 0; r < n; r++) {
      double response = a_[r * n + r];
      if (flips_[r] >= kMaxFlips) {  // let go: only its damping responds
        slope_[r] = -dt * damp_[r] / (1 + response * dt * damp_[r]);
        continue;
      }
      if (!result_[r].clamped) {
        slope_[r] = -lin_alpha_[r] / (1 + lin_alpha_[r] * response);
        continue;
      }
      // a clamped row: the slope on the side where it is smaller (away from a kink)
      double step = 1e-7 * (1 + std::fabs(rest_[r]));
      double up = RowSolve(r, rest_[r] + step, dt, d).x, down = RowSolve(r, rest_[r] - step, dt, d).x;
      double hd = dt * damp_[r], shrink = 1 / (1 + response * hd);
      double rise = (up - result_[r].x) / step, fall = (result_[r].x - down) / step;
      double slope_x = std::fabs(rise) < std::fabs(fall) ? rise : fall;
      // y = -hd*(base + reff*x - qvel), base and reff as in RowSolve
      slope_[r] = slope_x - hd * (shrink + response * shrink * slope_x);
    }
    for (int r = 0; r < n; r++) {
      rhs_[r] = result_[r].x + result_[r].y - slope_[r] * (rest_[r] - vfree_[r]);
    }
    if (!SymmetricSolve(a_.data(), slope_.data(), rhs_.data(), n, &sym_rows_, &sym_h_, &sym_b_)) {
      for (int r = 0; r < n; r++) {
        const double* row = a_.data() + r * n;
        for (int s = 0; s < n; s++) q_[r * n + s] = (s == r ? 1 : 0) - (s == r ? 0 : slope_[r] * row[s]);
      }
      if (!LuSolve(q_.data(), rhs_.data(), n)) return false;
    }
    for (int r = 0; r < n; r++) {
      if (!std::isfinite(rhs_[r])) return false;
      // keep the split of the new total impulse; only the sum matters for the next step
      x_[r] = rhs_[r];
      y_[r] = 0;
    }
    Velocities();
  }
  return false;
}

int CoupledSolver::Sweep(const mjModel* m, const mjData* d, double dt) {
  int n = nrow_;

  // split the starting impulses into drive and damping parts at their predicted velocities; a
  // drive whose unclamped impulse is inside its envelope is done unless another row moves it
  LinearGuess(m, d);
  bool any = false;
  for (int r = 0; r < n; r++) {
    double v1 = v_[r];
    int k = rows_[r].drive;
    bool drive = k >= 0 && request_[k].active;
    y_[r] = drive ? -dt * damp_[r] * (v1 - qvel_[r]) : w_[r];
    x_[r] = drive ? w_[r] - y_[r] : 0;
    any |= drive && !Inside(request_[k].params, dt, x_[r], v1);
    released_[r] = -1;
    flips_[r] = 0;
    if (drive) effort_[k] = x_[r] / dt;
  }
  if (!any) return 0;
  FullResponse(d);

  return Settle(d, dt);
}

int CoupledSolver::Settle(const mjData* d, double dt) {
  // a few Newton steps usually settle every drive; Gauss-Seidel finishes what they leave
  int n = nrow_;
  int iterations = 0;
  if (Newton(d, dt, &iterations)) return iterations;
  for (int r = 0; r < n; r++) stale_[r] = 1;
  int sweeps = 0;
  for (; sweeps < kMaxSweeps; sweeps++) {
    bool solved = false;
    for (int r = 0; r < n; r++) {
      if (!stale_[r]) continue;
      stale_[r] = 0;
      solved = true;
      double response = a_[r * n + r];
      double held = x_[r] + y_[r];
      double rest = v_[r] - response * held;  // velocity without this row's own impulses
      RowResult result = RowSolve(r, rest, dt, d);
      Track(r, result);
      double delta = result.x + result.y - held;
      x_[r] = result.x;
      y_[r] = result.y;
      v_[r] = rest + response * (result.x + result.y);
      if (delta == 0 || !std::isfinite(delta)) continue;
      const double* column = a_.data() + r * n;
      for (int s = 0; s < n; s++) {
        double dv = column[s] * delta;
        if (s == r || dv == 0) continue;
        v_[s] += dv;
        if (std::fabs(dv) > kTolerance * (1 + std::fabs(v_[s]))) stale_[s] = 1;
      }
    }
    if (!solved) break;
  }
  return iterations + sweeps;
}

}  // namespace drive_envelope::mujoco_plugin
