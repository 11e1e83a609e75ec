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

// TreeStep refactors with rows whose |1 + slope*A_rr| is above this (alpha*A_rr below its
// inverse, 1e4): there the tree solve's velocities match A*w to rounding
constexpr double kTreeConditioning = 1e-4;

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
    // A_rr: read only by acceleration drives and where it may vanish (constrained.cc's A_c);
    // before Response on M's tree it is at least 1/D_rr > 0
    double response = response_ ? adiag_[r] : 1;
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

bool CoupledSolver::TreeSolve(const mjModel* m, const mjData* d, const mjtNum* c, const mjtNum* alpha) {
  // every row's law w = c - alpha*v1 at once. With v1 = vfree + M^-1 P' w that is
  // (M + P' diag(alpha) P) dv = P' (c - alpha*vfree), v1 = vfree + dv at the rows: M's own sparsity
  // (the tree), so no block of M^-1 is needed. Writes w_ and v_ (a row whose numbers are not
  // finite: w 0, v vfree) and keeps the factor and dv (TreeUpdate); false when the factorization
  // fails (a pivot not > mjMINVAL: alpha < 0 can make the matrix indefinite) or a row was not finite
  int n = nrow_, nv = m->nv;
  mjtNum* x = delta_.data();
  for (int i = 0; i < nv; i++) x[i] = 0;
  for (int r = 0; r < n; r++) x[rows_[r].dof] = c[r] - alpha[r] * vfree_[r];
  bool factored = TreeFactor(m, d, alpha);
  if (factored) TreeBack(m, x);
  for (int r = 0; r < n; r++) {
    double v1 = vfree_[r] + (factored ? x[rows_[r].dof] : 0);
    w_[r] = c[r] - alpha[r] * v1;
    v_[r] = v1;
    if (!std::isfinite(w_[r]) || !std::isfinite(v1)) {
      w_[r] = 0;
      v_[r] = vfree_[r];  // a row set to 0 no longer moves the others: the caller recomputes them
      factored = false;
    }
  }
  return factored;
}

bool CoupledSolver::TreeFactor(const mjModel* m, const mjData* d, const mjtNum* alpha) {
  // h_ = L'*D*L of M + P' diag(alpha) P in place (hdinv_ = D^-1), as MuJoCo factors M
  // (mj_factorI). The loop is mj_factorI's own because mujoco.h (4.0) has no call that factors a
  // matrix other than d->M: mj_factorM writes d->qLD, which the constraint solver reads after the
  // drives
  int nv = m->nv;
  const int *rowadr = m->M_rowadr, *rownnz = m->M_rownnz, *colind = m->M_colind;
  mjtNum* h = h_.data();
  mju_copy(h, d->M, m->nC);
  for (int r = 0; r < nrow_; r++) {
    int dof = rows_[r].dof;
    h[rowadr[dof] + rownnz[dof] - 1] += alpha[r];
  }
  for (int k = nv - 1; k >= 0; k--) {
    int start = rowadr[k], end = start + rownnz[k] - 1;
    double pivot = h[end];
    if (!(pivot > mjMINVAL && std::isfinite(pivot))) return false;
    double inverse = 1 / pivot;
    hdinv_[k] = inverse;
    for (int adr = end - 1; adr >= start; adr--) {
      // row i < k of the lower triangle, minus row k's part: distinct rows of h, so no aliasing
      mjtNum* target = h + rowadr[colind[adr]];
      const mjtNum* source = h + start;
      double scale = -h[adr] * inverse;
      int count = rownnz[colind[adr]];
#pragma GCC ivdep
      for (int j = 0; j < count; j++) target[j] += source[j] * scale;
    }
    for (int adr = start; adr < end; adr++) h[adr] *= inverse;
  }
  return true;
}

void CoupledSolver::TreeBack(const mjModel* m, mjtNum* x) const {
  // x = (L'*D*L)^-1 x with TreeFactor's factor, as mj_solveLD
  SolveTransposed(m, h_.data(), x);
  SolveDiagonalLower(m, h_.data(), hdinv_.data(), x);
}

bool CoupledSolver::TreeUpdate(const mjModel* m) {
  // TreeStep where few rows' laws differ from the linear guess's (the set changed_; the others keep
  // w = lin_c - lin_alpha*v). With H the guess's factored matrix, M dv = P' w reads
  // H dv = P'(lin_c - lin_alpha*vfree) + U t: U the changed rows' unit columns, t their impulse
  // beyond their guess law, t = w - (lin_c - lin_alpha*v). So dv = dv_guess + Z t with Z = H^-1 U
  // (one solve a changed row) and, at the changed rows, v = v_guess + S t with S = U'Z. Their laws
  // a*w + b*v = g (law_a_, law_b_, law_g_: a = 0 holds a row at a velocity, a speed cap without a
  // slope) give the small system [diag(a) + diag(b - a*lin_alpha) S] t = g - a*lin_c
  // - (b - a*lin_alpha) v_guess, instead of a new factor. False where it is singular
  int nv = m->nv, count = static_cast<int>(changed_.size());
  mjtNum* dv = dv_.data();
  for (int i = 0; i < nv; i++) dv[i] = guess_dv_[i];
  for (int j = 0; j < count; j++) {
    mjtNum* z = zc_.data() + j * nv;
    for (int i = 0; i < nv; i++) z[i] = 0;
    z[rows_[changed_[j]].dof] = 1;
    TreeBack(m, z);
  }
  for (int i = 0; i < count; i++) {
    int r = changed_[i], dof = rows_[r].dof;
    double a = law_a_[i], coupling = law_b_[i] - a * lin_alpha_[r];
    for (int j = 0; j < count; j++) q_[i * count + j] = (i == j ? a : 0) + coupling * zc_[j * nv + dof];
    rhs_[i] = law_g_[i] - a * lin_c_[r] - coupling * (vfree_[r] + guess_dv_[dof]);
  }
  if (!LuSolve(q_.data(), rhs_.data(), count)) return false;
  for (int j = 0; j < count; j++) {
    const mjtNum* z = zc_.data() + j * nv;
    double t = rhs_[j];
    if (t != 0) {
      for (int i = 0; i < nv; i++) dv[i] += z[i] * t;
    }
  }
  for (int r = 0; r < nrow_; r++) {
    double v1 = vfree_[r] + dv[rows_[r].dof];
    w_[r] = lin_c_[r] - lin_alpha_[r] * v1;
    v_[r] = v1;
  }
  for (int j = 0; j < count; j++) w_[changed_[j]] += rhs_[j];
  for (int r = 0; r < nrow_; r++) {
    if (!std::isfinite(w_[r]) || !std::isfinite(v_[r])) return false;
  }
  return true;
}

void CoupledSolver::TreeVelocities(const mjModel* m, const mjData* d) {
  // v = vfree + A*(x + y) with A = P M^-1 P' from M's factor (HalfSolve, then the rows' z as in
  // FreeVelocity), where Velocities needs the whole block A
  mjtNum* force = row_force_.data();
  for (int i = 0; i < m->nv; i++) force[i] = 0;
  for (int r = 0; r < nrow_; r++) force[rows_[r].dof] = x_[r] + y_[r];
  HalfSolve(m, d, force);
  RowsOf(d, force, v_.data());
  for (int r = 0; r < nrow_; r++) v_[r] += vfree_[r];
}

void CoupledSolver::LinearGuess(const mjModel* m, const mjData* d) {
  // the solve's starting point: every row's unclamped law at once (TreeSolve). Newton and the
  // sweeps then clamp and correct it, so a failed factorization only costs iterations: it falls
  // back to one Jacobi step from vfree
  guess_factored_ = TreeSolve(m, d, lin_c_.data(), lin_alpha_.data());
  if (guess_factored_) {
    guess_dv_.assign(delta_.begin(), delta_.end());
    return;
  }
  int n = nrow_;
  for (int r = 0; r < n; r++) {
    w_[r] = std::isfinite(w_[r]) ? w_[r] : 0;
  }
  FullResponse(d);
  for (int r = 0; r < n; r++) x_[r] = w_[r], y_[r] = 0;
  Velocities();
}

CoupledSolver::RowResult CoupledSolver::RowSolve(int r, double rest, double dt, const mjData* d) {
  solves_++;
  double response = adiag_[r];

  // implicit joint damping y = -h*D'*(v1 - qvel) folded in: v1 = base + reff*x, linear in x
  double hd = dt * damp_[r];
  double scale = 1 / (1 + response * hd);
  double reff = response * scale;
  double base = (rest + response * hd * qvel_[r]) * scale;

  RowResult out;
  int k = rows_[r].drive;
  if (k >= 0 && request_[k].active && (!hold_ || flips_[r] < kMaxFlips)) {
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

bool CoupledSolver::Newton(const mjModel* m, const mjData* d, double dt, int* iterations) {
  // Newton's method on the fixed point w_r = G_r(rest_r(w)), where G_r is a row's own solve
  // (PD, clamp, damping) as a function of the velocity the other rows give it,
  // rest_r = vfree_r + sum_{s != r} A_rs w_s. G_r is piecewise linear: its slope is
  // -alpha/(1 + alpha*A_rr) where the clamp did not bind, else measured (the clamp is only ever
  // evaluated, never rewritten). Each step solves (I - diag(slope)*A_off) w = G - slope*(rest - vfree)
  int n = nrow_;
  for (int it = 0; it < kMaxNewton; it++) {
    double residual = 0;
    for (int r = 0; r < n; r++) {
      double response = adiag_[r];
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
      // v_ is read after the solve only by the sweeps that follow a failed Newton (Settle), and
      // the constrained loop recomputes its velocities from the efforts: no update is needed
      return true;
    }
    Slopes(d, dt);
    if (!(tree_ && TreeStep(m, d)) && !DenseStep(d)) return false;
  }
  return false;
}

bool CoupledSolver::Cycling() const {
  // only without holding (after a converged Newton): a drive back and forth across the jump
  if (hold_) return false;
  for (int r = 0; r < nrow_; r++) {
    if (flips_[r] > kMaxFlips) return true;
  }
  return false;
}

bool CoupledSolver::HeldLetGo(const mjData* d, double dt) {
  // a drive held let go after kMaxFlips is consistent only where its own solve, not held, lets
  // go too at the velocity the others give it; else (a Franka Panda's shoulder at 1.7 of its
  // 2.175 rad/s, held at 0 for 13 steps where its law asks for 87 N*m) Gauss-Seidel takes over
  for (int r = 0; r < nrow_; r++) {
    if (flips_[r] < kMaxFlips) continue;
    hold_ = false;
    RowResult own = RowSolve(r, rest_[r], dt, d);
    hold_ = true;
    if (own.x != 0) return false;
  }
  return true;
}

void CoupledSolver::Slopes(const mjData* d, double dt) {
  // each row's dG_r/d(rest_r) at this step's rest_ and result_
  for (int r = 0; r < nrow_; r++) {
    double response = adiag_[r];
    lawful_[r] = 0;
    if (flips_[r] >= kMaxFlips) {  // let go: only its damping responds
      slope_[r] = -dt * damp_[r] / (1 + response * dt * damp_[r]);
      continue;
    }
    if (!result_[r].clamped) {  // its own law: lin_c, lin_alpha (Prepare)
      slope_[r] = -lin_alpha_[r] / (1 + lin_alpha_[r] * response);
      lawful_[r] = 1;
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
}

bool CoupledSolver::TreeStep(const mjModel* m, const mjData* d) {
  // the Newton step as a law per row on its end-of-step velocity: w_r = G_r + s_r*(rest_r - rest0_r)
  // with rest_r = v_r - A_rr*w_r is a*w_r + b*v_r = g with a = 1 + s_r*A_rr, b = -s_r,
  // g = G_r - s_r*rest0_r (an unclamped row keeps its own law, lin_c/lin_alpha), solved on M's tree
  // instead of the dense block: an update of the linear guess's factor for a few changed rows
  // (TreeUpdate, any a), a new factor for many (TreeSolve, alpha = -s/a, c = g/a). A row held at
  // its speed line without a slope (speed_effort_gradient 0) has a = 0: its law is v = v_max, and
  // near it alpha grows the condition number of M + P' diag(alpha) P and c - alpha*v cancels (on
  // the example quadruped alpha*A_rr reached 1e10 and v missed A*w by 1e-5 [rad/s]): a new factor
  // takes only |a| > kTreeConditioning, the dense step the rest. False (nothing kept) where neither
  // tree path serves
  changed_.clear();
  bool finite_alpha = true;
  for (int r = 0; r < nrow_; r++) {
    if (lawful_[r]) continue;
    double s = slope_[r];
    law_a_[changed_.size()] = 1 + s * adiag_[r];
    law_b_[changed_.size()] = -s;
    law_g_[changed_.size()] = result_[r].x + result_[r].y - s * rest_[r];
    finite_alpha &= std::fabs(1 + s * adiag_[r]) > kTreeConditioning;
    changed_.push_back(r);
  }
  // a few changed rows: update the guess's factor; many: a new one (the cheaper, by count), unless
  // a row is held at a velocity (the update still beats the dense step there)
  int count = static_cast<int>(changed_.size());
  bool cheap = count * (solve_work_ + m->nv) + count * count * count < factor_work_;
  bool update = guess_factored_ && (cheap || !finite_alpha);
  if (!(update && TreeUpdate(m))) {
    if (!finite_alpha) return false;
    for (int r = 0; r < nrow_; r++) {
      step_alpha_[r] = lin_alpha_[r];
      step_c_[r] = lin_c_[r];
    }
    for (int j = 0; j < count; j++) {
      int r = changed_[j];
      step_alpha_[r] = law_b_[j] / law_a_[j];
      step_c_[r] = law_g_[j] / law_a_[j];
      if (!std::isfinite(step_alpha_[r]) || !std::isfinite(step_c_[r])) return false;
    }
    guess_factored_ = false;  // h_ is this step's factor from here on
    if (!TreeSolve(m, d, step_c_.data(), step_alpha_.data())) return false;
  }
  for (int r = 0; r < nrow_; r++) {
    // keep the split of the new total impulse; only the sum matters for the next step
    x_[r] = w_[r];
    y_[r] = 0;
  }
  // the velocities again from M's own factor, as Response's A: the residual that ends the Newton
  // steps then reads velocities consistent with the impulses by construction, and an inexact
  // step (rounding in an ill-conditioned update) costs an iteration, never a wrong answer
  TreeVelocities(m, d);
  return true;
}

bool CoupledSolver::DenseStep(const mjData* d) {
  // the Newton step on the block A: (I - diag(slope)*A_off) w = G - slope*(rest - vfree)
  int n = nrow_;
  FullResponse(d);
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
    x_[r] = rhs_[r];
    y_[r] = 0;
  }
  Velocities();
  return true;
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
  return Settle(m, d, dt);
}

int CoupledSolver::Settle(const mjModel* m, const mjData* d, double dt) {
  // a few Newton steps usually settle every drive; Gauss-Seidel finishes what they leave
  EnsureResponse(d);
  int n = nrow_;
  int iterations = 0;
  bool converged = Newton(m, d, dt, &iterations);
  if (converged && HeldLetGo(d, dt)) return iterations;
  if (converged) {  // Newton's answer holds a drive let go that would not: kept if the sweeps cycle
    held_x_.assign(x_.begin(), x_.end());
    held_y_.assign(y_.begin(), y_.end());
    held_effort_.assign(effort_.begin(), effort_.end());
  }
  FullResponse(d);  // the sweeps read A's columns
  for (int r = 0; r < n; r++) stale_[r] = 1;
  // Gauss-Seidel from Newton's last state. After a converged Newton no drive is held let go:
  // where a consistent state exists the sweeps get there, and where the drives cycle across the
  // jump Newton's answer stays. After a failed one the holding ends the cycles, as in Newton
  hold_ = !converged;
  if (converged) {  // count the switches anew: a drive that cycles in the sweeps too ends them
    for (int r = 0; r < n; r++) released_[r] = -1, flips_[r] = 0;
  }
  bool settled = false;
  int sweeps = 0;
  for (; sweeps < kMaxSweeps && !Cycling(); sweeps++) {
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
    if (!solved) {
      settled = true;
      break;
    }
  }
  hold_ = true;
  if (converged && !settled) {
    x_.assign(held_x_.begin(), held_x_.end());
    y_.assign(held_y_.begin(), held_y_.end());
    effort_.assign(held_effort_.begin(), held_effort_.end());
  }
  return iterations + sweeps;
}

}  // namespace drive_envelope::mujoco_plugin
