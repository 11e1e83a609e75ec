// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// drive_envelope.envelope: a MuJoCo actuator plugin with the PhysX articulation drive (implicit
// spring-damper) and the PhysX 5.6+ drive performance envelope. See README.md for the law.
//
// The drives' numbers live in the model (actuator_dynprm of each drive's effort actuator, see
// Slot) and are read at every step; the structure (which joints, which inputs) is fixed when an
// mjData is made. One solver per mjData, owned by the lowest instance of this plugin (the
// leader), computes the efforts of every drive of every instance together (coupled.h).

#ifndef DRIVE_ENVELOPE_PLUGIN_MUJOCO_ENVELOPE_H_
#define DRIVE_ENVELOPE_PLUGIN_MUJOCO_ENVELOPE_H_

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mjdata.h>
#include <mujoco/mjmodel.h>
#include <mujoco/mjtype.h>

#include "drive_math.h"

namespace drive_envelope::mujoco_plugin {

class CoupledSolver;

// control inputs, same bits and canonical order as MuJoCo's pid actuator (mjtCtrlInput)
enum Input : int { kInputPos = 1, kInputVel = 2, kInputFf = 4 };

// a drive's numbers: actuator_dynprm[mjNDYN*actuator + slot] of its effort actuator, SI
enum Slot : int {
  kSlotMaxEffort = 0,             // [N*m or N], or kNoLimit
  kSlotMaxActuatorVelocity = 1,   // [rad/s or m/s], or kNoLimit
  kSlotResistance = 2,            // velocity_dependent_resistance [N*m*s/rad or N*s/m]
  kSlotGradient = 3,              // speed_effort_gradient [(rad/s)/(N*m) or (m/s)/N]
  kSlotStiffness = 4,             // [N*m/rad or N/m] (force), [1/s^2] (acceleration)
  kSlotDamping = 5,               // [N*m*s/rad or N*s/m] (force), [1/s] (acceleration)
  kNumSlots = 6                   // slots 6..9 are reserved and must be 0
};

// largest finite number a slot may hold [SI]; larger ones overflow the step's arithmetic
constexpr double kParamBound = 1e12;

// max_effort or max_actuator_velocity without a limit (MuJoCo's MJCF writer cannot write inf)
constexpr double kNoLimit = -1;

// the six numbers of one drive, with kNoLimit turned into inf
struct DriveParams {
  double max_effort = 0;
  double max_actuator_velocity = 0;
  double velocity_dependent_resistance = 0;
  double speed_effort_gradient = 0;
  double stiffness = 0;
  double damping = 0;

  // reads actuator i's dynprm; returns -1, or the first bad slot (writing the reason to error)
  static int FromModel(const mjModel* m, int i, DriveParams* params, std::string* error);
};

// how the drives of a model are solved each step: the model's custom numeric kSolverNumeric,
// [solver, position_iterations, velocity_iterations, constraints], read at every step like the
// drives' numbers; absent: the exact coupled solve
constexpr char kSolverNumeric[] = "drive_envelope_solver";
enum class SolverKind : int { kExact = 0, kPgs = 1, kTgs = 2 };
constexpr int kMaxIterations = 255;  // PhysX's bound on an articulation's iteration counts

struct SolverSetting {
  SolverKind kind = SolverKind::kExact;
  int position_iterations = 1;   // [1, 255]: PGS's position sweeps, TGS's substeps
  int velocity_iterations = 0;   // [0, 255]; PGS runs at least one (PhysX's writeback sweep)
  bool constraints = false;      // exact only: the drives re-solved with MuJoCo's constraint solve

  // reads numeric id (-1: absent, the exact solve); on a bad value returns false and writes the
  // reason to error
  static bool FromModel(const mjModel* m, int id, SolverSetting* setting, std::string* error);
};

// the configuration of one plugin instance: structural, read when an mjData is made
struct InstanceConfig {
  DriveType drive_type = DriveType::kForce;
  int input = kInputPos;  // bitfield of Input

  // reads the plugin attributes; on bad input returns false and writes the reason to error
  static bool FromModel(const mjModel* m, int instance, InstanceConfig* config,
                        std::string* error);
};

// one driven DOF: a hinge or slide joint and the actuators that feed its inputs
struct Drive {
  int joint = -1;
  int dof = -1;
  int qpos = -1;
  int actuator = -1;             // effort actuator: carries the total effort, holds the numbers
  int input[3] = {-1, -1, -1};   // actuator of the pos, vel, ff inputs; -1: absent (0)
  std::vector<int> actuators;    // all of the drive's actuators (their outputs are written)
  DriveType drive_type = DriveType::kForce;
};

// every drive of this plugin in a model, and what else acts on their DOFs
struct Structure {
  std::vector<Drive> drives;     // in dof order (root to leaves)
  std::vector<int> native;       // actuators of no instance of this plugin (forces predicted)
  int solver_numeric = -1;       // id of the custom numeric kSolverNumeric, -1: none (exact)

  // builds it from all instances; on bad input returns false and writes the reason to error
  static bool Build(const mjModel* m, Structure* structure, std::string* error);
};

class Envelope {
 public:
  // returns an instance, or null after mju_warning on a bad configuration
  static std::unique_ptr<Envelope> Create(const mjModel* m, mjData* d, int instance);
  ~Envelope();

  // the leader writes every drive's total effort to d->actuator_force (idempotent); others: none
  void Compute(const mjModel* m, mjData* d, int instance);

  // the leader moves the drives' positions to PhysX's integration (solver pgs/tgs); others: none
  void Advance(const mjModel* m, mjData* d);

  // adds the plugin to MuJoCo's global registry
  static void RegisterPlugin();

  // diagnostics of the leader's last computation (0 for other instances): the iterations (Newton
  // steps plus Gauss-Seidel sweeps) and the drive solves (clamp evaluations) they took. Kept here,
  // not in plugin_state, so mjSTATE_FULLPHYSICS holds physics only (as MuJoCo's pid: nstate 0).
  int last_iterations() const { return last_iterations_; }
  int last_solves() const { return last_solves_; }
  // constraint solves (mj_fwdConstraint calls) the last computation ran itself (constraints=1)
  int last_constraint_solves() const { return last_constraint_solves_; }
  void ResetStats() { last_iterations_ = last_solves_ = last_constraint_solves_ = 0; }

 private:
  explicit Envelope(std::unique_ptr<CoupledSolver> solver);

  std::unique_ptr<CoupledSolver> solver_;  // leader only
  int last_iterations_ = 0;
  int last_solves_ = 0;
  int last_constraint_solves_ = 0;
};

// the lowest instance of this plugin in m (the leader), or -1
int LeaderInstance(const mjModel* m);

// "'name'" or "#id" of an actuator or joint, for messages
std::string ActuatorName(const mjModel* m, int id);
std::string JointName(const mjModel* m, int id);

// mju_warning, but each distinct message only once per process (init runs for every mjData)
void WarnOnce(const std::string& message);

}  // namespace drive_envelope::mujoco_plugin

#endif  // DRIVE_ENVELOPE_PLUGIN_MUJOCO_ENVELOPE_H_
