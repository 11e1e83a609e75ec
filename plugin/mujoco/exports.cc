// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// C entry points for tests and tools (ctypes): the C++ drive math on plain numbers (the clamp in
// its guarded default and in PhysX's exact arithmetic), the MuJoCo version the library was built
// against, and the solver's diagnostics of an instance.

#include <mujoco/mujoco.h>

#include "drive_math.h"
#include "envelope.h"

namespace dm = drive_envelope::mujoco_plugin;

extern "C" {

__attribute__((visibility("default"))) int drive_envelope_mujoco_header_version(void) {
  return mjVERSION_HEADER;
}

__attribute__((visibility("default"))) float drive_envelope_clamp_drive_impulse_f32(
    float joint_vel0, float drive_impulse0, float drive_impulse, float response,
    float max_joint_vel, float max_impulse, float speed_impulse_gradient,
    float velocity_dependent_resistance) {
  return dm::ClampDriveImpulse<float>(joint_vel0, drive_impulse0, drive_impulse, response,
                                      max_joint_vel, max_impulse, speed_impulse_gradient,
                                      velocity_dependent_resistance);
}

__attribute__((visibility("default"))) double drive_envelope_clamp_drive_impulse_f64(
    double joint_vel0, double drive_impulse0, double drive_impulse, double response,
    double max_joint_vel, double max_impulse, double speed_impulse_gradient,
    double velocity_dependent_resistance) {
  return dm::ClampDriveImpulse<double>(joint_vel0, drive_impulse0, drive_impulse, response,
                                       max_joint_vel, max_impulse, speed_impulse_gradient,
                                       velocity_dependent_resistance);
}

__attribute__((visibility("default"))) float drive_envelope_clamp_drive_impulse_physx_f32(
    float joint_vel0, float drive_impulse0, float drive_impulse, float response,
    float max_joint_vel, float max_impulse, float speed_impulse_gradient,
    float velocity_dependent_resistance) {
  return dm::ClampDriveImpulsePhysx<float>(joint_vel0, drive_impulse0, drive_impulse, response,
                                           max_joint_vel, max_impulse, speed_impulse_gradient,
                                           velocity_dependent_resistance);
}

__attribute__((visibility("default"))) double drive_envelope_clamp_drive_impulse_physx_f64(
    double joint_vel0, double drive_impulse0, double drive_impulse, double response,
    double max_joint_vel, double max_impulse, double speed_impulse_gradient,
    double velocity_dependent_resistance) {
  return dm::ClampDriveImpulsePhysx<double>(joint_vel0, drive_impulse0, drive_impulse, response,
                                            max_joint_vel, max_impulse, speed_impulse_gradient,
                                            velocity_dependent_resistance);
}

// drive_type: 0 force, 1 acceleration
__attribute__((visibility("default"))) double drive_envelope_implicit_drive_effort(
    double stiffness, double damping, double position_error, double velocity,
    double target_velocity, double response, double dt, int drive_type) {
  return dm::ImplicitDriveEffort(stiffness, damping, position_error, velocity, target_velocity,
                                 response, dt,
                                 drive_type ? dm::DriveType::kAcceleration : dm::DriveType::kForce);
}

// the leader instance's diagnostics of its last computation (iterations, drive solves), from its
// mjData::plugin_data entry; 0 on success, -1 for a null instance
__attribute__((visibility("default"))) int drive_envelope_solver_stats(const void* instance_data,
                                                                     int* iterations, int* solves) {
  if (instance_data == nullptr) return -1;
  const auto* envelope = static_cast<const drive_envelope::mujoco_plugin::Envelope*>(instance_data);
  *iterations = envelope->last_iterations();
  *solves = envelope->last_solves();
  return 0;
}

// constraint solves (mj_fwdConstraint) the leader's last computation ran itself: 0 unless the
// solver setting has constraints = 1 and the step had constraint rows
__attribute__((visibility("default"))) int drive_envelope_constraint_solves(
    const void* instance_data, int* constraint_solves) {
  if (instance_data == nullptr) return -1;
  const auto* envelope = static_cast<const drive_envelope::mujoco_plugin::Envelope*>(instance_data);
  *constraint_solves = envelope->last_constraint_solves();
  return 0;
}

}  // extern "C"
