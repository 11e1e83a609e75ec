// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// drive_envelope.envelope: a MuJoCo actuator plugin with the PhysX articulation drive (implicit
// spring-damper) and the PhysX 5.6+ drive performance envelope. See README.md for the law.

#ifndef DRIVE_ENVELOPE_PLUGIN_MUJOCO_ENVELOPE_H_
#define DRIVE_ENVELOPE_PLUGIN_MUJOCO_ENVELOPE_H_

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mjdata.h>
#include <mujoco/mjmodel.h>
#include <mujoco/mjtype.h>

#include "drive_math.h"

namespace drive_envelope::mujoco_plugin {

// control inputs, same bits and canonical order as MuJoCo's pid actuator (mjtCtrlInput)
enum Input : int { kInputPos = 1, kInputVel = 2, kInputFf = 4 };

struct EnvelopeConfig {
  double stiffness = 0;                      // [N*m/rad or N/m] (force), [1/s^2] (acceleration)
  double damping = 0;                        // [N*m*s/rad or N*s/m] (force), [1/s] (acceleration)
  double max_effort = 0;                     // [N*m or N]
  double max_actuator_velocity = INFINITY;   // [rad/s or m/s]
  double velocity_dependent_resistance = 0;  // [N*m*s/rad or N*s/m]
  double speed_effort_gradient = 0;          // [(rad/s)/(N*m) or (m/s)/N]
  DriveType drive_type = DriveType::kForce;
  int input = kInputPos;                     // bitfield of Input

  // reads the plugin attributes; on bad input returns false and writes the reason to error
  static bool FromModel(const mjModel* m, int instance, EnvelopeConfig* config,
                        std::string* error);
};

// one driven DOF: a hinge or slide joint and the actuators that feed its inputs
struct Drive {
  int joint = -1;
  int dof = -1;
  int qpos = -1;
  int ctrl[3] = {-1, -1, -1};  // control address of the pos, vel, ff inputs; -1: absent (0)
  int actuator = -1;           // first actuator: carries the drive's total effort
  std::vector<int> outputs;    // force addresses of all the drive's actuators
  std::vector<int> chain;      // dofs where L^-T e_dof can be nonzero, descending (static)
  bool ctrllimited[3] = {false, false, false};
  double ctrlrange[3][2] = {{0, 0}, {0, 0}, {0, 0}};
};

class Envelope {
 public:
  // returns an instance, or null after mju_warning on a bad configuration
  static std::unique_ptr<Envelope> Create(const mjModel* m, int instance);

  // writes the drive's total effort to d->actuator_force (idempotent)
  void Compute(const mjModel* m, mjData* d, int instance);

  // adds the plugin to MuJoCo's global registry
  static void RegisterPlugin();

 private:
  Envelope(EnvelopeConfig config, std::vector<Drive> drives, int leader, int nv);

  // leader only: unconstrained acceleration from the smooth forces known at actuation time
  void ComputeSmoothAcceleration(const mjModel* m, mjData* d);

  // diagonal entry of M^-1 for a drive's dof, from the factorization already in d->qLD
  double Response(const mjModel* m, const mjData* d, const Drive& drive);

  EnvelopeConfig config_;
  std::vector<Drive> drives_;
  int leader_;                   // instance that computes the shared acceleration
  std::vector<mjtNum> force_;    // leader: smooth forces besides the drives (nv)
  std::vector<mjtNum> qacc_;     // leader: M^-1 * force_ (nv)
  std::vector<mjtNum> chain_;    // scratch for Response (nv), zero between calls
};

}  // namespace drive_envelope::mujoco_plugin

#endif  // DRIVE_ENVELOPE_PLUGIN_MUJOCO_ENVELOPE_H_
