// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// PhysX's articulation iteration over the drives (solver "pgs" or "tgs", see README.md, "Solvers"):
// what Isaac Lab trains with, instead of the exact coupled solve of solve.cc. PhysX solves an
// articulation's drives as velocity rows in Gauss-Seidel sweeps from the root to the leaves
// (DyFeatherstoneArticulation.cpp, solveInternalJointConstraintRecursive): each row's response is
// the articulation's (M^-1)_ii (getImpulseSelfResponse), each clamped impulse moves every DOF of
// the tree through M^-1's column i, and the implicit drive law and clamp are PhysX's
// (computeImplicitDriveParams, computeDriveImpulse, clampDriveImpulse: drive_math.h).
//
// PGS (DySolverControl.cpp): loads act once over the step; position_iterations sweeps, then
// max(1, velocity_iterations) sweeps ("PGS solver always runs at least one velocity iteration").
// TGS (DyTGSDynamics.cpp, external forces every substep as PhysX runs through USD): each position
// iteration is a substep of dt/position_iterations that applies the loads over the substep and
// clamps that substep's impulse against max_effort*substep, the spring seeing the displacement
// since the step began; then velocity_iterations sweeps re-clamp the step's total drive impulse
// at the current velocity with no new request. MuJoCo then integrates the step with the total
// effort: its end-of-step velocity is the sweeps' own (the rows are linear in the impulses), its
// position q + h*v1 rather than PhysX's (PGS: the velocity after the position sweeps; TGS: per
// substep).

#include <cmath>
#include <vector>

#include <mujoco/mujoco.h>

#include "coupled.h"

namespace drive_envelope::mujoco_plugin {

void CoupledSolver::Propagate(int r, double impulse) {
  // an impulse on row r moves every row through M^-1's column r (A is symmetric: row r)
  if (impulse == 0 || !std::isfinite(impulse)) return;
  const double* column = a_.data() + r * nrow_;
  for (int s = 0; s < nrow_; s++) v_[s] += column[s] * impulse;
}

void CoupledSolver::Visit(int r, Pass pass, double dt, double span, double elapsed) {
  // one row of one sweep: the drive's block of solveInternalJointConstraintRecursive, then the
  // row's implicit joint damping (MuJoCo's; PhysX's articulations have none), each changing the
  // velocities before the next row sees them
  solves_++;
  double response = a_[r * nrow_ + r];
  int k = rows_[r].drive;
  if (k >= 0 && request_[k].active) {
    const DriveParams& p = request_[k].params;

    // a TGS substep clamps its own impulse (PhysX's isPerStep); the others the step's total
    double applied = pass == Pass::kTgsSubstep ? 0.0 : x_[r];
    double external = request_[k].ff * span;  // the joint force: effort that counts, not driven
    double request = pass == Pass::kTgsVelocity
                         ? applied
                         : ComputeDriveImpulse(desc_[r], applied, v_[r], moved_[r], elapsed);
    double clamped = ClampDriveImpulse<double>(v_[r], applied + external, request + external,
                                               response, p.max_actuator_velocity,
                                               p.max_effort * span, p.speed_effort_gradient / span,
                                               p.velocity_dependent_resistance * span) -
                     external;
    double delta = clamped - applied;
    if (std::isfinite(delta)) {
      x_[r] += delta;
      Propagate(r, delta);
    }
  }
  double hd = dt * damp_[r];
  if (hd > 0) {
    // the step's damping impulse y = -h*D'*(v1 - qvel), solved for this row with the others held
    double delta = (-hd * (v_[r] - qvel_[r]) - y_[r]) / (1 + response * hd);
    if (std::isfinite(delta)) {
      y_[r] += delta;
      Propagate(r, delta);
    }
  }
}

void CoupledSolver::BiasVelocity(const mjModel* m, mjData* d, double dt) {
  // TGS applies the gravity and the external and joint forces per substep
  // (applyTgsSubstepForces) but the velocity-dependent bias (Coriolis, centrifugal) once, before
  // the first substep: that part of MuJoCo's smooth force is -qfrc_bias minus gravity's J'*m*g
  mjtNum* force = bias_force_.data();
  for (int i = 0; i < m->nv; i++) force[i] = -d->qfrc_bias[i];
  if (!(m->opt.disableflags & mjDSBL_GRAVITY)) {
    for (int b = 1; b < m->nbody; b++) {
      mjtNum weight[3], zero[3] = {0, 0, 0};
      mju_scl3(weight, m->opt.gravity, -m->body_mass[b]);  // minus: taken out of -qfrc_bias
      if (weight[0] || weight[1] || weight[2]) {
        mj_applyFT(m, d, weight, zero, d->xipos + 3 * b, b, force);  // mj_applyFT only reads d
      }
    }
  }
  HalfSolve(m, d, force);
  RowsOf(d, force, bias_.data());
  for (int r = 0; r < nrow_; r++) bias_[r] *= dt;
}

int CoupledSolver::Articulation(const mjData* d, double dt, const SolverSetting& setting) {
  int n = nrow_;
  bool tgs = setting.kind == SolverKind::kTgs;
  int substeps = setting.position_iterations;
  double step = tgs ? dt / substeps : dt;

  // the step's drive laws, set up once from the start of the step (PhysX's setupInternalConstraints)
  for (int r = 0; r < n; r++) {
    x_[r] = y_[r] = moved_[r] = 0;
    int k = rows_[r].drive;
    if (k < 0 || !request_[k].active) continue;
    const Request& q = request_[k];
    desc_[r] = ComputeImplicitDriveParams(
        drives_[k].drive_type, q.params.stiffness, q.params.damping, step, dt, a_[r * n + r],
        q.target_pos - d->qpos[drives_[k].qpos], q.target_vel, tgs);
  }

  // the loads' velocity change over the step: the smooth forces (vfree) and the joint forces
  for (int r = 0; r < n; r++) v_[r] = vfree_[r];
  for (int r = 0; r < n; r++) {
    int k = rows_[r].drive;
    if (k >= 0 && request_[k].active) Propagate(r, request_[k].ff * dt);
  }
  int sweeps = 0;
  if (!tgs) {
    for (int it = 0; it < substeps; it++, sweeps++) {
      for (int r = 0; r < n; r++) Visit(r, Pass::kPgs, dt, dt, 0);
    }
    for (int r = 0; r < n; r++) shift_[r] = v_[r] * dt;  // PGS: q1 = q0 + v*dt, v of the position sweeps
    int velocity = setting.velocity_iterations > 1 ? setting.velocity_iterations : 1;
    for (int it = 0; it < velocity; it++, sweeps++) {
      for (int r = 0; r < n; r++) Visit(r, Pass::kPgs, dt, dt, 0);
    }
  } else {
    // the bias acts before the first substep, the loads over each (BiasVelocity)
    for (int r = 0; r < n; r++) rest_[r] = (v_[r] - qvel_[r] - bias_[r]) / substeps;
    for (int r = 0; r < n; r++) v_[r] = qvel_[r] + bias_[r];
    double elapsed = 0;
    for (int it = 0; it < substeps; it++, sweeps++) {
      for (int r = 0; r < n; r++) v_[r] += rest_[r];  // applyTgsSubstepForces
      for (int r = 0; r < n; r++) Visit(r, Pass::kTgsSubstep, dt, step, elapsed);
      for (int r = 0; r < n; r++) moved_[r] += v_[r] * step;  // updateDeltaMotion
      elapsed += step;
    }
    for (int r = 0; r < n; r++) shift_[r] = moved_[r];
    for (int it = 0; it < setting.velocity_iterations; it++, sweeps++) {
      for (int r = 0; r < n; r++) Visit(r, Pass::kTgsVelocity, dt, dt, elapsed);
    }
  }

  // MuJoCo integrates q1 = q0 + h*v1 with the final velocity; PhysX with its own (Advance)
  for (int r = 0; r < n; r++) shift_[r] -= dt * v_[r];
  shift_pending_ = true;

  // the drive's total effort over the step: its impulse and the joint force
  for (int r = 0; r < n; r++) {
    int k = rows_[r].drive;
    if (k < 0 || !request_[k].active) continue;
    double effort = (x_[r] + request_[k].ff * dt) / dt;
    effort_[k] = std::isfinite(effort) ? effort : 0;
  }
  return sweeps;
}

void CoupledSolver::Advance(const mjModel* m, mjData* d) {
  // only after a step that computed once and integrated once: RK4 evaluates four stages and
  // integrates their mix, so there the positions stay MuJoCo's
  if (!shift_pending_) return;
  shift_pending_ = false;
  if (m->opt.integrator == mjINT_RK4) return;
  for (int r = 0; r < nrow_; r++) {
    int joint = m->dof_jntid[rows_[r].dof];
    int type = m->jnt_type[joint];
    if ((type != mjJNT_HINGE && type != mjJNT_SLIDE) || !std::isfinite(shift_[r])) continue;
    d->qpos[m->jnt_qposadr[joint]] += shift_[r];
  }
}

}  // namespace drive_envelope::mujoco_plugin
