// Copyright 2026 The drive-envelope authors. BSD-3-Clause.

#include "coupled.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

namespace drive_envelope::mujoco_plugin {
namespace {

// the dofs that L^-T * e_dof can reach, in descending order: dof, then every column of a reached
// row (its ancestors, plus any fill); fixed by the sparsity of M, so computed once per row
std::vector<int> Chain(const mjModel* m, int dof) {
  std::vector<char> reached(m->nv, 0);
  std::vector<int> chain;
  reached[dof] = 1;
  for (int k = dof; k >= 0; k--) {
    if (!reached[k]) continue;
    chain.push_back(k);
    int start = m->M_rowadr[k];
    for (int adr = start; adr < start + m->M_rownnz[k] - 1; adr++) reached[m->M_colind[adr]] = 1;
  }
  return chain;
}

// MuJoCo's mj_actuatorDamping: damping that actuators add to joint j (and their poly terms)
double ActuatorDamping(const mjModel* m, int j, mjtNum poly[mjNPOLY]) {
  int id = m->jnt_actuatorid[j];
  if (id == -1) return 0;
  double damping = 0;
  for (int k = id >= 0 ? id : 0; k < (id >= 0 ? id + 1 : m->nactuator); k++) {
    bool on_joint = m->actuator_trnid[2 * k] == j && (m->actuator_trntype[k] == mjTRN_JOINT ||
                                                      m->actuator_trntype[k] == mjTRN_JOINTINPARENT);
    if (id < -1 && !on_joint) continue;
    double gear = m->actuator_gear[6 * m->actuator_outadr[k]];
    damping += m->actuator_damping[k] * gear * gear;
    for (int p = 0; p < mjNPOLY; p++) poly[p] += m->actuator_dampingpoly[mjNPOLY * k + p] * gear * gear;
  }
  return damping;
}

// whether dof i has any damping for MuJoCo to integrate implicitly
bool Damped(const mjModel* m, int i) {
  mjtNum poly[mjNPOLY] = {0};
  if (m->dof_damping[i] > 0 || ActuatorDamping(m, m->dof_jntid[i], poly) > 0) return true;
  for (int p = 0; p < mjNPOLY; p++) {
    if (m->dof_dampingpoly[mjNPOLY * i + p] != 0 || poly[p] != 0) return true;
  }
  return false;
}

// d(damping force)/d(qvel) of dof i at qvel, as MuJoCo's implicit damping uses it (mjd_xPolyForce)
double DampingDerivative(const mjModel* m, const mjData* d, int i) {
  mjtNum poly[mjNPOLY];
  for (int p = 0; p < mjNPOLY; p++) poly[p] = m->dof_dampingpoly[mjNPOLY * i + p];
  double result = m->dof_damping[i] + ActuatorDamping(m, m->dof_jntid[i], poly);
  double speed = std::fabs(d->qvel[i]), power = 1;
  for (int p = 0; p < mjNPOLY; p++) {
    power *= speed;
    result += (p + 2) * poly[p] * power;
  }
  return result;
}

// mju_isBad and mju_clip, inlined: ReadRequests calls them for every input at every step
bool IsBad(double x) { return !(x >= -mjMAXVAL && x <= mjMAXVAL); }
double Clip(double x, double low, double high) { return x < low ? low : (x > high ? high : x); }

bool Disabled(const mjModel* m, int actuator) {
  int group = m->actuator_group[actuator];
  return group >= 0 && group <= 30 && (m->opt.disableactuator & (1 << group));
}

// the control of actuator i as MuJoCo's native actuators read it: delayed through the history
// buffer when the actuator has a delay, then clamped to its ctrlrange
double ReadControl(const mjModel* m, const mjData* d, int i) {
  int adr = m->actuator_ctrladr[i];
  double u = d->ctrl[adr];
  if (m->actuator_delay[i] > 0 && m->actuator_history[2 * i] > 0) {
    mjtNum result = 0;
    const mjtNum* read = mj_readCtrl(m, d, i, d->time, &result, m->actuator_history[2 * i + 1]);
    u = read ? *read : result;
  }
  if (!(m->opt.disableflags & mjDSBL_CLAMPCTRL) && m->actuator_ctrllimited[adr]) {
    u = Clip(u, m->actuator_ctrlrange[2 * adr], m->actuator_ctrlrange[2 * adr + 1]);
  }
  return u;
}

}  // namespace

CoupledSolver::CoupledSolver(const mjModel* m, Structure structure)
    : drives_(std::move(structure.drives)),
      native_(std::move(structure.native)),
      solver_numeric_(structure.solver_numeric) {
  // rows: every drive, and every damped dof without one (its implicit damping couples the drives)
  std::vector<int> row_of(m->nv, -1);
  for (size_t k = 0; k < drives_.size(); k++) row_of[drives_[k].dof] = static_cast<int>(k);
  std::vector<std::vector<int>> members(m->nv);  // rows whose chain holds each dof, ascending
  for (int i = 0; i < m->nv; i++) {
    if (row_of[i] < 0 && !Damped(m, i)) continue;
    Row row;
    row.dof = i;
    row.drive = row_of[i];
    for (int k : Chain(m, i)) members[k].push_back(static_cast<int>(rows_.size()));
    rows_.push_back(row);
  }
  nrow_ = static_cast<int>(rows_.size());

  // dof-major layout of Z = L^-T [e_dof of every row]: the z values of dof k sit at
  // zd_[member_adr_[k] + i] for its i-th member row; every update below runs over a dof's members,
  // which are independent (throughput, not latency, bound)
  member_adr_.assign(m->nv, 0);
  member_num_.assign(m->nv, 0);
  for (int k = 0; k < m->nv; k++) {
    member_adr_[k] = static_cast<int>(member_row_.size());
    member_num_[k] = static_cast<int>(members[k].size());
    member_row_.insert(member_row_.end(), members[k].begin(), members[k].end());
    if (!members[k].empty()) dofs_.push_back(k);
  }
  std::reverse(dofs_.begin(), dofs_.end());  // descending: a dof's value is final when reached
  for (Row& row : rows_) {
    const std::vector<int>& own = members[row.dof];
    int index = static_cast<int>(std::find(own.begin(), own.end(), &row - rows_.data()) - own.begin());
    row.self = member_adr_[row.dof] + index;
  }

  // each off-diagonal entry of M's row k sends k's values to an ancestor, whose members include
  // k's: where each of k's members sits among the ancestor's. In MuJoCo's depth-first dof order
  // a dof's members (the rows in its subtree) are consecutive rows, so these are plain offsets;
  // other orders keep the explicit positions
  contiguous_ = true;
  for (int k : dofs_) {
    const std::vector<int>& own = members[k];
    for (size_t i = 1; i < own.size(); i++) contiguous_ &= own[i] == own[0] + static_cast<int>(i);
  }
  for (int k : dofs_) {
    Dof dof;
    dof.first = members[k][0];
    dof.entry_adr = static_cast<int>(entries_.size());
    for (int adr = m->M_rowadr[k]; adr < m->M_rowadr[k] + m->M_rownnz[k] - 1; adr++) {
      int ancestor = m->M_colind[adr];
      entries_.push_back(adr);
      entries_.push_back(member_adr_[ancestor]);
      entries_.push_back(static_cast<int>(map_.size()));
      const std::vector<int>& up = members[ancestor];
      for (int r : members[k]) {
        map_.push_back(static_cast<int>(std::find(up.begin(), up.end(), r) - up.begin()));
      }
    }
    dof.entry_num = (static_cast<int>(entries_.size()) - dof.entry_adr) / 3;
    dof_info_.push_back(dof);
  }

  int n = nrow_;
  request_.resize(drives_.size());
  force_.assign(m->nv, 0);
  zd_.assign(member_row_.size(), 0);
  a_.assign(n * n, 0);
  for (auto* v : {&vfree_, &damp_, &qvel_, &x_, &y_, &v_, &w_, &lin_c_, &lin_alpha_, &rhs_, &step_c_, &step_alpha_}) {
    v->assign(n, 0);
  }
  q_.assign(n * n, 0);
  sym_rows_.reserve(n);
  sym_h_.reserve(n * n);
  sym_b_.reserve(n);
  free_.reserve(n);
  fixed_.reserve(n);
  effort_.assign(drives_.size(), 0);
  stale_.assign(n, 0);
  released_.assign(n, -1);
  flips_.assign(n, 0);
  rest_.assign(n, 0);
  slope_.assign(n, 0);
  result_.assign(n, RowResult());
  desc_.assign(n, ImplicitDriveDesc());
  moved_.assign(n, 0);
  shift_.assign(n, 0);
  bias_.assign(n, 0);
  adiag_.assign(n, 0);
  h_.assign(m->nC, 0);
  hdinv_.assign(m->nv, 0);
  delta_.assign(m->nv, 0);
  bias_force_.assign(m->nv, 0);
  row_force_.assign(m->nv, 0);
  lawful_.assign(n, 0);
  changed_.reserve(n);
  law_a_.assign(n, 0);
  law_b_.assign(n, 0);
  law_g_.assign(n, 0);
  guess_dv_.assign(m->nv, 0);
  dv_.assign(m->nv, 0);
  zc_.assign(static_cast<size_t>(n) * m->nv, 0);
  for (int k = 0; k < m->nv; k++) {
    for (int adr = m->M_rowadr[k]; adr < m->M_rowadr[k] + m->M_rownnz[k] - 1; adr++) {
      factor_work_ += m->M_rownnz[m->M_colind[adr]];
    }
  }
  solve_work_ = 2 * (m->nC - m->nv) + m->nv;
  warned_.assign(drives_.size() + 2, 0);
  checked_.assign(drives_.size(), 0);
  checked_prm_.assign(drives_.size() * mjNDYN, 0);
  checked_params_.assign(drives_.size(), DriveParams());
  for (const Drive& drive : drives_) acceleration_ |= drive.drive_type == DriveType::kAcceleration;
}

void CoupledSolver::Warn(int key, const char* format, const char* name, const char* detail) {
  // once per mjData and cause: a bad number set between steps must not flood the log
  if (warned_[key]) return;
  warned_[key] = 1;
  mju_warning(format, name, detail);
}

void CoupledSolver::ReadRequests(const mjModel* m, mjData* d, double dt) {
  bool bad = false;
  for (size_t k = 0; k < drives_.size(); k++) {
    const Drive& drive = drives_[k];
    Request& q = request_[k];
    q.active = false;
    if (Disabled(m, drive.actuator)) continue;
    if (!CachedParams(m, k, &q.params)) continue;
    double u[3] = {0, 0, 0};
    for (int s = 0; s < 3; s++) {
      int i = drive.input[s];
      if (i < 0 || Disabled(m, i)) continue;  // a disabled input contributes nothing
      u[s] = ReadControl(m, d, i);
      bad |= IsBad(u[s]);
    }
    q.target_pos = u[0];
    q.target_vel = u[1];
    q.ff = u[2];
    q.active = true;
  }

  // MuJoCo zeroes every control when one is bad (mjWARN_BADCTRL); the drives read them alike
  for (int i = 0; i < m->nu && !bad; i++) bad = IsBad(d->ctrl[i]);
  if (bad) {
    for (Request& q : request_) q.target_pos = q.target_vel = q.ff = 0;
  }
}

bool CoupledSolver::CachedParams(const mjModel* m, size_t k, DriveParams* params) {
  // the numbers are read at every step (a user may change them between steps), but checked only
  // when their bits differ from the last ones that passed: a bad number never passes, so it is
  // checked (and warned about, once) at every step it stays
  int actuator = drives_[k].actuator;
  const mjtNum* prm = m->actuator_dynprm + mjNDYN * actuator;
  mjtNum* seen = checked_prm_.data() + mjNDYN * k;
  if (checked_[k] && std::memcmp(prm, seen, sizeof(mjtNum) * mjNDYN) == 0) {
    *params = checked_params_[k];
    return true;
  }
  std::string error;
  checked_[k] = 0;
  if (DriveParams::FromModel(m, actuator, params, &error) >= 0) {
    std::string name = ActuatorName(m, actuator);
    Warn(static_cast<int>(k), "drive_envelope.envelope: actuator %s: %s; it gives no effort",
         name.c_str(), error.c_str());
    return false;
  }
  std::memcpy(seen, prm, sizeof(mjtNum) * mjNDYN);
  checked_params_[k] = *params;
  checked_[k] = 1;
  return true;
}

void CoupledSolver::SmoothVelocity(const mjModel* m, mjData* d, double dt) {
  int nv = m->nv;
  mjtNum* force = force_.data();

  // smooth forces MuJoCo has at actuation time: passive - bias + applied + J'*xfrc_applied
  for (int i = 0; i < nv; i++) {
    force[i] = d->qfrc_passive[i] - d->qfrc_bias[i] + d->qfrc_applied[i];
  }
  for (int b = 1; b < m->nbody; b++) {
    const mjtNum* xfrc = d->xfrc_applied + 6 * b;
    if (xfrc[0] || xfrc[1] || xfrc[2] || xfrc[3] || xfrc[4] || xfrc[5]) {
      mj_applyFT(m, d, xfrc, xfrc + 3, d->xipos + 3 * b, b, force);
    }
  }

  // other actuators, already computed (MuJoCo runs plugins after its native actuators), with
  // the forcerange clamp MuJoCo applies after the plugins
  for (int i : native_) {
    if (Disabled(m, i)) continue;
    for (int o = m->actuator_outadr[i]; o < m->actuator_outadr[i] + m->actuator_outnum[i]; o++) {
      double f = d->actuator_force[o];
      if (m->actuator_forcelimited[i] && m->actuator_outnum[i] == 1) {
        f = mju_clip(f, m->actuator_forcerange[2 * i], m->actuator_forcerange[2 * i + 1]);
      }
      if (f == 0) continue;
      for (int adr = d->moment_rowadr[o]; adr < d->moment_rowadr[o] + d->moment_rownnz[o]; adr++) {
        force[d->moment_colind[adr]] += d->actuator_moment[adr] * f;
      }
    }
  }

  // gravity compensation routed through the actuators (jnt_actgravcomp)
  if (m->flg_gravcomp && !(m->opt.disableflags & mjDSBL_GRAVITY) &&
      mju_norm3(m->opt.gravity) > 0) {
    static const int kDofNum[4] = {6, 3, 1, 1};
    for (int j = 0; j < m->njnt; j++) {
      if (!m->jnt_actgravcomp[j]) continue;
      for (int k = 0; k < kDofNum[m->jnt_type[j]]; k++) {
        force[m->jnt_dofadr[j] + k] += d->qfrc_gravcomp[m->jnt_dofadr[j] + k];
      }
    }
  }

  if (keep_smooth_) smooth_.assign(force, force + nv);  // constraints=1 forms qfrc_smooth from it
  HalfSolve(m, d, force);
  for (int r = 0; r < nrow_; r++) qvel_[r] = d->qvel[rows_[r].dof];
}

void CoupledSolver::HalfSolve(const mjModel* m, const mjData* d, mjtNum* force) const {
  // only the rows of M^-1*force are needed: e_dof'*M^-1*force = z'*D^-1*(L^-T*force), so one
  // triangular solve here and a dot product per row once z is known (RowsOf)
  SolveTransposed(m, d->qLD, force);
}

void CoupledSolver::RowsOf(const mjData* d, const mjtNum* half, double* out) const {
  // (M^-1*force) at each row's dof, from HalfSolve's result and the rows' z (Response)
  const mjtNum* dinv = d->qLDiagInv;
  for (int r = 0; r < nrow_; r++) out[r] = 0;
  for (int k : dofs_) {
    double gk = half[k] * dinv[k];
    const double* z = zd_.data() + member_adr_[k];
    const int* rows = member_row_.data() + member_adr_[k];
    for (int i = 0; i < member_num_[k]; i++) out[rows[i]] += z[i] * gk;
  }
}

void CoupledSolver::FreeVelocity(double dt, const mjModel* m, const mjData* d) {
  // end-of-step velocity of each row without any drive: qvel + h*(M^-1*force)_dof, finishing
  // HalfSolve's triangular solve (D^-1, then L^-1 as mj_solveLD): cheaper than the rows' z of
  // Response, which a step inside every envelope never needs
  mjtNum* x = force_.data();
  SolveDiagonalLower(m, d->qLD, d->qLDiagInv, x);
  for (int r = 0; r < nrow_; r++) vfree_[r] = qvel_[r] + dt * x[rows_[r].dof];
}

void CoupledSolver::ImplicitDamping(const mjModel* m, const mjData* d, double dt) {
  // Euler (unless eulerdamp is disabled), implicit and implicitfast integrate joint damping
  // implicitly: the velocity update solves with M + h*D'(qvel); the rows carry that term
  int flags = m->opt.disableflags, integrator = m->opt.integrator;
  bool implicit = !(flags & mjDSBL_DAMPER) &&
                  ((integrator == mjINT_EULER && !(flags & mjDSBL_EULERDAMP)) ||
                   integrator == mjINT_IMPLICIT || integrator == mjINT_IMPLICITFAST);
  for (int r = 0; r < nrow_; r++) {
    damp_[r] = implicit ? DampingDerivative(m, d, rows_[r].dof) : 0;
  }
}

void CoupledSolver::Response(const mjData* d) {
  // once per step, where a step needs it (EnsureResponse). M = L'*D*L, so A = (M^-1) over the
  // rows = Z'*D^-1*Z with Z = L^-T*[e_dof of each row]: solve for every row at once, dof by dof
  // from the leaves, then add each dof's rank-1 part of A
  const mjtNum* dinv = d->qLDiagInv;
  const mjtNum* ld = d->qLD;
  double* zd = zd_.data();
  int n = nrow_;
  for (size_t i = 0; i < zd_.size(); i++) zd[i] = 0;
  for (const Row& row : rows_) zd[row.self] = 1;
  for (size_t t = 0; t < dofs_.size(); t++) {
    int k = dofs_[t];
    const double* z = zd + member_adr_[k];
    int count = member_num_[k];
    const int* entry = entries_.data() + dof_info_[t].entry_adr;
    for (int e = 0; e < dof_info_[t].entry_num; e++, entry += 3) {
      double l = ld[entry[0]];
      double* up = zd + entry[1];
      const int* where = map_.data() + entry[2];
      if (contiguous_) {
        up += where[0];
        for (int i = 0; i < count; i++) up[i] -= l * z[i];
      } else {
        for (int i = 0; i < count; i++) up[where[i]] -= l * z[i];
      }
    }
  }

  // the diagonal now (each row's response, the same sums in the same order as FullResponse's);
  // the whole block only when a drive is outside its envelope (FullResponse)
  for (int r = 0; r < n; r++) adiag_[r] = 0;
  for (size_t t = 0; t < dofs_.size(); t++) {
    int k = dofs_[t];
    const double* z = zd + member_adr_[k];
    const int* rows = member_row_.data() + member_adr_[k];
    for (int i = 0; i < member_num_[k]; i++) adiag_[rows[i]] += z[i] * dinv[k] * z[i];
  }
  full_ = false;
  response_ = true;
}

void CoupledSolver::EnsureResponse(const mjData* d) {
  if (!response_) Response(d);
}

void CoupledSolver::FullResponse(const mjData* d) {
  if (full_) return;
  EnsureResponse(d);
  full_ = true;
  const mjtNum* dinv = d->qLDiagInv;
  const double* zd = zd_.data();
  int n = nrow_;
  for (int i = 0; i < n * n; i++) a_[i] = 0;
  for (size_t t = 0; t < dofs_.size(); t++) {
    int k = dofs_[t];
    const double* z = zd + member_adr_[k];
    const int* rows = member_row_.data() + member_adr_[k];
    int count = member_num_[k], first = dof_info_[t].first;
    for (int i = 0; i < count; i++) {
      double zi = z[i] * dinv[k];
      if (contiguous_) {
        double* arow = a_.data() + (first + i) * n + first;
        for (int j = i; j < count; j++) arow[j] += zi * z[j];
      } else {
        double* arow = a_.data() + rows[i] * n;
        for (int j = i; j < count; j++) arow[rows[j]] += zi * z[j];
      }
    }
  }
  for (int a = 0; a < n; a++) {
    for (int b = a + 1; b < n; b++) a_[b * n + a] = a_[a * n + b];
  }
}

int CoupledSolver::Compute(const mjModel* m, mjData* d) {
  solves_ = 0;
  constraint_solves_ = 0;
  shift_pending_ = false;
  double dt = m->opt.timestep;
  bool valid = dt > 0 && std::isfinite(dt);
  if (!valid) {
    std::string value = std::to_string(dt);
    Warn(static_cast<int>(drives_.size()),
         "drive_envelope.envelope: option %s = %s: expected a finite number > 0 [s]; the drives "
         "give no effort", "'timestep'", value.c_str());
  } else {
    ReadRequests(m, d, dt);
  }

  // the solver's numbers are read at every step, as the drives' are; made bad between steps,
  // the drives give no effort until they are fixed
  SolverSetting setting;
  std::string problem;
  if (valid && !SolverSetting::FromModel(m, solver_numeric_, &setting, &problem)) {
    Warn(static_cast<int>(drives_.size()) + 1, "drive_envelope.envelope: %s%s; the drives give no effort",
         problem.c_str(), "");
    valid = false;
  }
  bool any = false;
  for (size_t k = 0; k < drives_.size(); k++) {
    if (!valid) request_[k].active = false;
    any |= request_[k].active;
    effort_[k] = 0;
  }
  int sweeps = 0;
  keep_smooth_ = setting.kind == SolverKind::kExact && setting.constraints;
  if (any) {
    SmoothVelocity(m, d, dt);
    ImplicitDamping(m, d, dt);
    response_ = full_ = false;
    tree_ = true;
    FreeVelocity(dt, m, d);
    if (setting.kind == SolverKind::kExact) {
      if (acceleration_) EnsureResponse(d);  // Prepare's laws per unit inertia read A_rr
      Prepare(d, dt);
      sweeps = Sweep(m, d, dt);
      if (setting.constraints) sweeps += Constrained(m, d, dt);
    } else {
      FullResponse(d);
      if (setting.kind == SolverKind::kTgs) BiasVelocity(m, d, dt);
      sweeps = Articulation(d, dt, setting);
    }
  }
  for (size_t k = 0; k < drives_.size(); k++) {
    const Drive& drive = drives_[k];
    for (int i : drive.actuators) d->actuator_force[m->actuator_outadr[i]] = 0;
    if (request_[k].active) d->actuator_force[m->actuator_outadr[drive.actuator]] = effort_[k];
  }
  return sweeps;
}

}  // namespace drive_envelope::mujoco_plugin
