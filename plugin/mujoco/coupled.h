// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// The coupled drive solve of one step: every envelope drive of the model at once. A linear solve of
// the unclamped laws, then Newton steps on the drives' own solves (each one PhysX's implicit drive
// and clamp with the others held, as its articulation solver treats a drive row), then Gauss-Seidel
// sweeps if needed. See README.md ("Control law") and docs/mujoco.md (the parameter layout).

#ifndef DRIVE_ENVELOPE_PLUGIN_MUJOCO_COUPLED_H_
#define DRIVE_ENVELOPE_PLUGIN_MUJOCO_COUPLED_H_

#include <vector>

#include <mujoco/mjdata.h>
#include <mujoco/mjmodel.h>
#include <mujoco/mjtype.h>

#include "envelope.h"

namespace drive_envelope::mujoco_plugin {

// at most this many Newton steps per step, then at most this many Gauss-Seidel sweeps
constexpr int kMaxNewton = 8;
constexpr int kMaxSweeps = 50;

// converged: no row's own solve moves its velocity by more than kTolerance * (1 + |v|) [rad/s or
// m/s]; in Gauss-Seidel a row is solved again when another row's update moved it by more
constexpr double kTolerance = 1e-12;

// a drive that switches between letting go and a nonzero effort this many times in one solve
// lets go for the rest of it (the release is the clamp's one jump; it could cycle)
constexpr int kMaxFlips = 2;

// the two triangular passes of a solve with a factor L'*D*L on M's sparsity (mj_solveLD's, on
// MuJoCo's qLD or the drives' own factor): x = L'^-1 x, and x = L^-1 D^-1 x (dinv = D^-1)
inline void SolveTransposed(const mjModel* m, const mjtNum* ld, mjtNum* x) {
  const int *rowadr = m->M_rowadr, *rownnz = m->M_rownnz, *colind = m->M_colind;
  for (int k = m->nv - 1; k > 0; k--) {
    double xk = x[k];
    if (xk == 0) continue;
    for (int adr = rowadr[k], end = rowadr[k] + rownnz[k] - 1; adr < end; adr++) {
      x[colind[adr]] -= ld[adr] * xk;
    }
  }
}

inline void SolveDiagonalLower(const mjModel* m, const mjtNum* ld, const mjtNum* dinv,
                               mjtNum* x) {
  const int *rowadr = m->M_rowadr, *rownnz = m->M_rownnz, *colind = m->M_colind;
  for (int k = 0; k < m->nv; k++) {
    double sum = 0;
    for (int adr = rowadr[k], end = rowadr[k] + rownnz[k] - 1; adr < end; adr++) {
      sum += ld[adr] * x[colind[adr]];
    }
    x[k] = x[k] * dinv[k] - sum;
  }
}

class CoupledSolver {
 public:
  CoupledSolver(const mjModel* m, Structure structure);

  // writes every drive's total effort to d->actuator_force; returns the iterations (exact: Newton
  // steps plus Gauss-Seidel sweeps, 0 when the linear solve was inside every envelope; pgs/tgs:
  // the sweeps over the drives)
  int Compute(const mjModel* m, mjData* d);

  // pgs/tgs: moves the drives' positions, which MuJoCo has just integrated with the end-of-step
  // velocity, to where PhysX integrates them (PGS: the velocity after the position sweeps; TGS:
  // per substep); called from the plugin's advance, once per Compute
  void Advance(const mjModel* m, mjData* d);

  // row solves (clamp evaluations) of the last Compute
  int solves() const { return solves_; }

  // MuJoCo constraint solves (mj_fwdConstraint) the last Compute ran itself (constraints=1)
  int constraint_solves() const { return constraint_solves_; }

 private:
  // one unknown of the solve: a drive's DOF, or a damped DOF without a drive
  struct Row {
    int dof = -1;
    int drive = -1;            // index in drives_, -1: a damped DOF without a drive
    int self = 0;              // address in zd_ of the row's value at its own dof
  };

  // a dof that some row's chain holds: its off-diagonal entries of M, (qLD address, ancestor's
  // address in zd_, address in map_ of where each member sits among the ancestor's) triples
  struct Dof {
    int first = 0;             // its first member row
    int entry_adr = 0;
    int entry_num = 0;
  };

  // a row's own solve: drive impulse x, damping impulse y, the drive's effort, and whether the
  // envelope changed the request
  struct RowResult {
    double x = 0, y = 0, effort = 0;
    bool clamped = false;
  };

  // per-step quantities of a drive row, read from the model and data
  struct Request {
    bool active = false;       // false: zero effort (disabled group, bad numbers, bad dt)
    DriveParams params;
    double target_pos = 0, target_vel = 0, ff = 0;
  };

  void Warn(int key, const char* format, const char* name, const char* detail);
  void ReadRequests(const mjModel* m, mjData* d, double dt);
  bool CachedParams(const mjModel* m, size_t k, DriveParams* params);
  void SmoothVelocity(const mjModel* m, mjData* d, double dt);
  void ImplicitDamping(const mjModel* m, const mjData* d, double dt);
  void Response(const mjData* d);
  void EnsureResponse(const mjData* d);
  void FullResponse(const mjData* d);
  void FreeVelocity(double dt, const mjModel* m, const mjData* d);
  void HalfSolve(const mjModel* m, const mjData* d, mjtNum* force) const;
  void RowsOf(const mjData* d, const mjtNum* half, double* out) const;
  void Prepare(const mjData* d, double dt);
  bool TreeSolve(const mjModel* m, const mjData* d, const mjtNum* c, const mjtNum* alpha);
  bool TreeFactor(const mjModel* m, const mjData* d, const mjtNum* alpha);
  void TreeBack(const mjModel* m, mjtNum* x) const;
  bool TreeUpdate(const mjModel* m);
  void TreeVelocities(const mjModel* m, const mjData* d);
  void LinearGuess(const mjModel* m, const mjData* d);
  RowResult RowSolve(int r, double rest, double dt, const mjData* d);
  void Track(int r, const RowResult& result);
  void Velocities();
  bool Newton(const mjModel* m, const mjData* d, double dt, int* iterations);
  bool HeldLetGo(const mjData* d, double dt);
  bool Cycling() const;
  void Slopes(const mjData* d, double dt);
  bool TreeStep(const mjModel* m, const mjData* d);
  bool DenseStep(const mjData* d);
  int Sweep(const mjModel* m, const mjData* d, double dt);
  int Settle(const mjModel* m, const mjData* d, double dt);

  // constraints=1 (constrained.cc): Newton steps on the drives with MuJoCo's constraint solve in
  // the loop, each linearised with the constrained Hessian M + h*D' + J'*D*J; returns the steps
  int Constrained(const mjModel* m, mjData* d, double dt);
  void ConstrainedVelocity(const mjModel* m, mjData* d, double dt);
  double Violation(double dt) const;
  bool ConstrainedResponse(const mjModel* m, mjData* d, double dt);

  // PhysX's articulation iteration (articulation.cc): from the free velocities and A, the rows
  // in one Gauss-Seidel sweep per iteration, root to leaves; returns the sweeps
  enum class Pass { kPgs, kTgsSubstep, kTgsVelocity };
  int Articulation(const mjData* d, double dt, const SolverSetting& setting);
  void Visit(int r, Pass pass, double dt, double span, double elapsed);
  void Propagate(int r, double impulse);
  void BiasVelocity(const mjModel* m, mjData* d, double dt);

  std::vector<Drive> drives_;
  std::vector<int> native_;
  int solver_numeric_ = -1;
  std::vector<Row> rows_;
  int nrow_ = 0;
  int solves_ = 0;

  // static sparsity: for each dof, the rows whose chain (dof and its ancestors, where L^-T e_dof
  // can be nonzero) holds it, member_row_[member_adr_[k] ...] (member_num_[k] of them)
  std::vector<int> member_adr_, member_num_, member_row_;
  std::vector<int> dofs_;        // dofs with members, descending
  std::vector<Dof> dof_info_;    // per entry of dofs_
  std::vector<int> entries_, map_;
  bool contiguous_ = true;       // every dof's members are consecutive rows (depth-first order)

  // scratch, reused every step
  std::vector<Request> request_;
  std::vector<mjtNum> force_, zd_;
  std::vector<double> a_, vfree_, damp_, qvel_, x_, y_, v_, effort_;
  std::vector<mjtNum> w_, lin_c_, lin_alpha_, q_, rhs_;
  std::vector<mjtNum> step_c_, step_alpha_;  // Newton: each row's law of the step (TreeStep)
  std::vector<char> lawful_;             // per row: its step law is the linear guess's (Slopes)
  std::vector<int> changed_;             // the rows whose law is not (TreeStep)
  std::vector<mjtNum> law_a_, law_b_, law_g_;  // their laws a*w + b*v = g, by index in changed_
  bool guess_factored_ = false;          // h_ holds the linear guess's factor, guess_dv_ its dv
  std::vector<mjtNum> guess_dv_, dv_;    // over the dofs
  std::vector<mjtNum> zc_;               // TreeUpdate: H^-1 on each changed row's unit column
  int factor_work_ = 0, solve_work_ = 0;  // multiply-adds of TreeFactor and TreeBack
  std::vector<int> free_, fixed_;
  std::vector<char> stale_, warned_;
  std::vector<char> checked_;            // per drive: checked_prm_ holds numbers that passed
  std::vector<mjtNum> checked_prm_;      // per drive, its dynprm at the last check (mjNDYN each)
  std::vector<DriveParams> checked_params_;  // and what they read as
  bool acceleration_ = false;            // some drive is an acceleration drive
  std::vector<int> released_, flips_;  // per row: last result was 0 (-1: none yet), switches
  bool hold_ = true;  // a row past kMaxFlips lets go (Newton); false in the Gauss-Seidel sweeps
  std::vector<double> held_x_, held_y_, held_effort_;  // Newton's answer while the sweeps try
  std::vector<double> rest_, slope_;
  std::vector<int> sym_rows_;            // Newton: the rows of the symmetric system (SymmetricSolve)
  std::vector<mjtNum> sym_h_, sym_b_;    // its matrix and right side
  std::vector<RowResult> result_;
  std::vector<ImplicitDriveDesc> desc_;  // per row, the step's drive law (pgs/tgs)
  std::vector<double> adiag_;            // per row, A_rr (Response; a_ only after FullResponse)
  bool response_ = false;                // zd_ and adiag_ hold this step's (Response)
  bool full_ = false;                    // a_ holds this step's A
  bool tree_ = true;                     // A = P M^-1 P' (TreeSolve serves), not constrained.cc's
  std::vector<mjtNum> h_, hdinv_, delta_;  // the linear guess's sparse factor and solution
  std::vector<double> moved_;            // per row, displacement since the step began (tgs)
  std::vector<double> shift_;            // per row, PhysX's position minus MuJoCo's [rad or m]
  bool shift_pending_ = false;
  std::vector<double> bias_;             // per row, h*(M^-1 * velocity-dependent bias) (tgs)
  std::vector<mjtNum> bias_force_;       // scratch over the dofs
  std::vector<mjtNum> row_force_;        // scratch over the dofs (TreeVelocities)

  // constraints=1 (constrained.cc)
  bool keep_smooth_ = false;             // SmoothVelocity keeps the smooth force in smooth_
  int constraint_solves_ = 0;
  std::vector<mjtNum> smooth_;           // qfrc_smooth without the drives (nv)
  std::vector<mjtNum> warm_;             // MuJoCo's qacc_warmstart, restored after the loop (nv)
  std::vector<mjtNum> cacc_, cfactor_;   // end-of-step acceleration (nv), sparse factor (nC)
  std::vector<mjtNum> cdinv_;            // its 1/diag (nv)
  std::vector<mjtNum> hess_, unit_, col_;  // dense M + h*D' + J'*D*J (nv*nv), solve scratch (nv)
  std::vector<mjtNum> jar_;              // J*qacc - aref (nefc, grown as needed)
  std::vector<double> cv_;               // per row, MuJoCo's end-of-step velocity [rad/s or m/s]
  std::vector<double> damp0_;            // per row, the integrator's damping derivative
  std::vector<double> best_effort_;      // per drive, the checked efforts closest to inside
};

}  // namespace drive_envelope::mujoco_plugin

#endif  // DRIVE_ENVELOPE_PLUGIN_MUJOCO_COUPLED_H_
