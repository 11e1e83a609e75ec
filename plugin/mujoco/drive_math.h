// Copyright 2026 The drive-envelope authors. BSD-3-Clause.
//
// The PhysX drive of one DOF, header-only and free of MuJoCo types: the implicit PD impulse and
// the performance-envelope clamp. These are C++ ports of the Python core
// (drive_envelope.implicit_drive_effort, drive_envelope.clamp_drive_impulse), which in turn follow
// PhysX 5.6+ (computeImplicitDriveParams, Dy::clampDriveImpulse). ClampDriveImpulse is the guarded
// default (the effort cap kept), ClampDriveImpulsePhysx PhysX's arithmetic (physx_exact=True); their
// float instantiations reproduce the Python float32 modes bit for bit (same operations, same
// order); build with -ffp-contract=off so that the compiler does not fuse them.

#ifndef DRIVE_ENVELOPE_PLUGIN_MUJOCO_DRIVE_MATH_H_
#define DRIVE_ENVELOPE_PLUGIN_MUJOCO_DRIVE_MATH_H_

#include <cfloat>
#include <cmath>
#include <limits>

namespace drive_envelope::mujoco_plugin {

// PhysX's absolute epsilon for near-zero denominators (PX_EPS_F32 = 2^-23)
constexpr double kPxEps = FLT_EPSILON;

// PhysX's sentinel for an absent bound (PX_MAX_F32)
constexpr double kPxMax = FLT_MAX;

enum class DriveType { kForce, kAcceleration };

// PxMax for floats (PhysX's selectMax): a > b ? a : b, so a NaN in a does not survive; this decides
// what a NaN bound turns into, e.g. (dev - inf) / inf
template <typename T>
inline T PxMax(T a, T b) { return a > b ? a : b; }

// PxMin for floats: a < b ? a : b
template <typename T>
inline T PxMin(T a, T b) { return a < b ? a : b; }

// numpy.maximum / numpy.minimum: a NaN in either operand wins (the guarded clamp's selects)
template <typename T>
inline T MaxNaN(T a, T b) { return (a > b || std::isnan(a)) ? a : b; }

template <typename T>
inline T MinNaN(T a, T b) { return (a < b || std::isnan(a)) ? a : b; }

template <typename T>
struct Bounds {
  T lower;
  T upper;
};

// (a + b) / denom; in the guard, where a + b overflows although a and b are finite (operands near
// the float range's end), a / denom + b / denom instead, which does not: PhysX's form would turn a
// finite bound into an infinite one and lose the curve
template <typename T, bool kExact>
inline T Quotient(T a, T b, T denom) {
  T sum = a + b;
  if (!kExact && std::isinf(sum) && std::isfinite(a) && std::isfinite(b)) {
    return a / denom + b / denom;
  }
  return sum / denom;
}

// feasible [lower, upper] of a positive request against |v| <= max - k*|x|; kExact: PhysX's
// arithmetic (FLT_MAX sentinels, select semantics), else the guard: inf sentinels, NaN-carrying
// selects, and a NaN lower bound when a flat curve says no (the clamp then returns 0)
template <typename T, bool kExact>
inline Bounds<T> BoundsPositive(T dev, T max, T denom1, T denom2, T impulse) {
  const T eps = static_cast<T>(kPxEps), zero = 0;
  const T big = kExact ? static_cast<T>(kPxMax) : std::numeric_limits<T>::infinity();

  // the curve is ignored
  if (std::fabs(denom2) < eps) return {-big, big};

  // denom1 ~ 0: the lower curve is a yes/no test on (dev - max)
  if (std::fabs(denom1) < eps) {
    T bound2 = Quotient<T, kExact>(dev, max, denom2);
    if (!kExact) {
      bool yes = std::fabs(dev - max) < eps || (dev - max) <= zero;
      return {yes ? zero : std::numeric_limits<T>::quiet_NaN(), bound2};
    }
    T bound1 = std::fabs(dev - max) < eps ? -big : ((dev - max) > zero ? big : -big);
    return {PxMax(zero, bound1), bound2};
  }
  T bound1 = Quotient<T, kExact>(dev, -max, denom1);
  T bound2 = Quotient<T, kExact>(dev, max, denom2);
  if (kExact) {
    if (denom1 >= zero) return {PxMax(zero, bound1), PxMin(bound2, impulse)};
    return {zero, PxMin(PxMin(bound1, bound2), impulse)};
  }
  if (denom1 >= zero) return {MaxNaN(zero, bound1), MinNaN(bound2, impulse)};
  return {zero, MinNaN(MinNaN(bound1, bound2), impulse)};
}

// feasible [lower, upper] of a negative (or zero) request
template <typename T, bool kExact>
inline Bounds<T> BoundsNegative(T dev, T max, T denom1, T denom2, T impulse) {
  const T eps = static_cast<T>(kPxEps), zero = 0;
  const T big = kExact ? static_cast<T>(kPxMax) : std::numeric_limits<T>::infinity();
  if (std::fabs(denom1) < eps) return {-big, big};
  if (std::fabs(denom2) < eps) {
    T bound1 = Quotient<T, kExact>(dev, -max, denom1);
    if (!kExact) {
      bool yes = std::fabs(dev + max) < eps || (dev + max) >= zero;
      return {bound1, yes ? zero : std::numeric_limits<T>::quiet_NaN()};
    }
    T bound2 = std::fabs(dev + max) < eps ? big : ((dev + max) > zero ? big : -big);
    return {bound1, PxMin(zero, bound2)};
  }
  T bound1 = Quotient<T, kExact>(dev, -max, denom1);
  T bound2 = Quotient<T, kExact>(dev, max, denom2);
  if (kExact) {
    if (denom2 >= zero) return {PxMax(bound1, impulse), PxMin(zero, bound2)};
    return {PxMax(PxMax(bound1, bound2), impulse), zero};
  }
  if (denom2 >= zero) return {MaxNaN(bound1, impulse), MinNaN(zero, bound2)};
  return {MaxNaN(MaxNaN(bound1, bound2), impulse), zero};
}

template <typename T, bool kExact>
inline Bounds<T> CurveBounds(T dev, T max, T response, T slope, T impulse) {
  if (impulse > T(0)) {
    return BoundsPositive<T, kExact>(dev, max, response - slope, response + slope, impulse);
  }
  return BoundsNegative<T, kExact>(dev, max, response + slope, response - slope, impulse);
}

template <typename T, bool kExact>
inline T ClampDriveImpulseImpl(T joint_vel0, T drive_impulse0, T drive_impulse, T response,
                               T max_joint_vel, T max_impulse, T speed_impulse_gradient,
                               T velocity_dependent_resistance) {
  const T zero = 0, one = 1;
  T dev = drive_impulse0 * response - joint_vel0;
  T resist = velocity_dependent_resistance;
  Bounds<T> b1 = CurveBounds<T, kExact>(dev, max_joint_vel, response, speed_impulse_gradient,
                                        drive_impulse);

  // eq. 1 written as |v| <= max_impulse/R - (1/R)*|x|; R = 0 is the box |x| <= max_impulse
  Bounds<T> b2 = {-max_impulse, max_impulse};
  bool plain = resist == zero;
  T inv = plain ? one : one / resist, limit = plain ? max_impulse : max_impulse / resist;

  // guarded: a resistance whose 1/R or max_impulse/R overflows acts as R = 0 (its R -> 0 limit)
  if (!kExact) plain = plain || !(std::isfinite(inv) && std::isfinite(limit));
  if (!plain) b2 = CurveBounds<T, kExact>(dev, limit, response, inv, drive_impulse);
  if (kExact) {
    T lower = PxMax(b1.lower, b2.lower);
    T upper = PxMin(b1.upper, b2.upper);

    // empty interval: even zero effort is infeasible, the drive lets go
    if (lower > upper) return zero;
    return PxMin(upper, PxMax(lower, drive_impulse));
  }

  // |x| <= max_impulse bounds the interval (implied by eq. 1, kept through rounding)
  T lower = MaxNaN(MaxNaN(b1.lower, b2.lower), -max_impulse);
  T upper = MinNaN(MinNaN(b1.upper, b2.upper), max_impulse);
  T clamped = MinNaN(upper, MaxNaN(lower, drive_impulse));

  // empty, or a NaN bound or request: the drive lets go
  if (!(lower <= upper) || std::isnan(clamped)) return zero;
  return clamped;
}

// clamp a requested total drive impulse x so that x and v(x) = v0 + r*(x - x0) satisfy
//   |v(x)| <= max_joint_vel - speed_impulse_gradient*|x|
//   |x|    <= max_impulse - velocity_dependent_resistance*|v(x)|   (|x| <= max_impulse if 0)
// keeps the sign of the request, never grows it, and returns 0 when no such x exists. this is
// the guarded clamp of drive_envelope.clamp_drive_impulse: |result| <= max_impulse and no NaN for
// every finite input (a resistance whose 1/R overflows acts as R = 0)
template <typename T>
inline T ClampDriveImpulse(T joint_vel0, T drive_impulse0, T drive_impulse, T response,
                           T max_joint_vel, T max_impulse, T speed_impulse_gradient,
                           T velocity_dependent_resistance) {
  return ClampDriveImpulseImpl<T, false>(joint_vel0, drive_impulse0, drive_impulse, response,
                                         max_joint_vel, max_impulse, speed_impulse_gradient,
                                         velocity_dependent_resistance);
}

// PhysX's Dy::clampDriveImpulse bit for bit (physx_exact=True in Python), flaws included
template <typename T>
inline T ClampDriveImpulsePhysx(T joint_vel0, T drive_impulse0, T drive_impulse, T response,
                                T max_joint_vel, T max_impulse, T speed_impulse_gradient,
                                T velocity_dependent_resistance) {
  return ClampDriveImpulseImpl<T, true>(joint_vel0, drive_impulse0, drive_impulse, response,
                                        max_joint_vel, max_impulse, speed_impulse_gradient,
                                        velocity_dependent_resistance);
}

// unclamped effort of one step of PhysX's implicit PD drive (spring and damper both implicit):
//   J = dt*k*(err - dt*v1) + dt*c*(vt - v1),  v1 = v + r*J
// so with a = dt*(dt*k + c): J = (dt*k*err + dt*c*vt - a*v) / (1 + a*r); returns J/dt.
// an acceleration drive uses a unit response and divides the impulse by r
inline double ImplicitDriveEffort(double stiffness, double damping, double position_error,
                                  double velocity, double target_velocity, double response,
                                  double dt, DriveType type) {
  double a = dt * (dt * stiffness + damping);
  double rhs = dt * stiffness * position_error + dt * damping * target_velocity - a * velocity;
  double impulse;
  if (type == DriveType::kForce) {
    // PhysX's guard: a DOF that does not respond gets no drive
    impulse = response > 0 ? (1.0 / (1.0 + a * response)) * rhs : 0.0;
  } else {
    impulse = rhs / ((1.0 + a) * response);
  }
  return impulse / dt;
}

// PhysX's ArticulationImplicitDriveDesc: the linear law of the implicit drive for one step, as
// computeImplicitDriveParams sets it up (the Python reference's implicit_drive_desc). The
// unclamped impulse of one solver iteration is ComputeDriveImpulse below [N*m*s or N*s]
struct ImplicitDriveDesc {
  double target_vel_plus_initial_bias = 0;  // [N*m*s or N*s]
  double bias_coefficient = 0;              // impulse per unit displacement in the step
  double vel_multiplier = 0;                // impulse per unit joint velocity (negative)
  double impulse_multiplier = 0;            // weight of the accumulated impulse: 1 - x (PGS), 1 (TGS)
  double target_pos_bias = 0;               // impulse per second elapsed (TGS) [N*m or N]
};

// computeImplicitDriveParams: dt is the span the spring integrates over (TGS: the substep, PGS:
// the step), sim_dt the step; response is the DOF's unit response (M^-1)_ii
inline ImplicitDriveDesc ComputeImplicitDriveParams(DriveType type, double stiffness,
                                                    double damping, double dt, double sim_dt,
                                                    double response, double geom_error,
                                                    double target_velocity, bool is_tgs) {
  double a = dt * (dt * stiffness + damping);
  double b = dt * (damping * target_velocity);
  double initial_bias = geom_error - (sim_dt - dt) * target_velocity;  // geom_error for PGS
  double x, scale;
  if (type == DriveType::kForce) {
    x = response > 0 ? 1.0 / (1.0 + a * response) : 0.0;
    scale = 1.0;
  } else {
    x = 1.0 / (1.0 + a);
    scale = 1.0 / response;  // recipResponse: gains per unit inertia
  }
  ImplicitDriveDesc desc;
  desc.bias_coefficient = stiffness * x * scale * dt;
  desc.target_vel_plus_initial_bias = x * b * scale + desc.bias_coefficient * initial_bias;
  desc.vel_multiplier = -x * a * scale;
  desc.impulse_multiplier = is_tgs ? 1.0 : 1.0 - x;
  desc.target_pos_bias = is_tgs ? desc.bias_coefficient * target_velocity : 0.0;
  return desc;
}

// computeDriveImpulse: the unclamped drive impulse of one solver iteration, from the impulse
// accumulated so far, the joint's current velocity, its displacement since the start of the step
// and the time elapsed in it (the last two TGS only, 0 for PGS) [N*m*s or N*s]
inline double ComputeDriveImpulse(const ImplicitDriveDesc& desc, double accumulated,
                                  double joint_velocity, double delta_position, double elapsed) {
  return accumulated * desc.impulse_multiplier + joint_velocity * desc.vel_multiplier +
         desc.target_vel_plus_initial_bias - delta_position * desc.bias_coefficient +
         elapsed * desc.target_pos_bias;
}

}  // namespace drive_envelope::mujoco_plugin

#endif  // DRIVE_ENVELOPE_PLUGIN_MUJOCO_DRIVE_MATH_H_
