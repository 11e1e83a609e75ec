// Copyright 2026 The drive-envelope authors. BSD-3-Clause.

#include "envelope.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

namespace drive_envelope::mujoco_plugin {
namespace {

constexpr char kPluginName[] = "drive_envelope.envelope";
constexpr char kAttrStiffness[] = "stiffness";
constexpr char kAttrDamping[] = "damping";
constexpr char kAttrMaxEffort[] = "max_effort";
constexpr char kAttrMaxActuatorVelocity[] = "max_actuator_velocity";
constexpr char kAttrVelocityDependentResistance[] = "velocity_dependent_resistance";
constexpr char kAttrSpeedEffortGradient[] = "speed_effort_gradient";
constexpr char kAttrDriveType[] = "drive_type";
constexpr char kAttrInput[] = "input";

// unit of each number attribute, for error messages (force drive; acceleration gains differ)
constexpr char kUnitStiffness[] = "[N*m/rad or N/m], or [1/s^2] for an acceleration drive";
constexpr char kUnitDamping[] = "[N*m*s/rad or N*s/m], or [1/s] for an acceleration drive";
constexpr char kUnitMaxEffort[] = "[N*m or N]";
constexpr char kUnitVelocity[] = "[rad/s or m/s]";
constexpr char kUnitResistance[] = "[N*m*s/rad or N*s/m]";
constexpr char kUnitGradient[] = "[(rad/s)/(N*m) or (m/s)/N]";

// reads a number attribute >= 0; inf only where allowed; a missing optional one keeps *out
bool ReadNumber(const mjModel* m, int instance, const char* attr, bool required, bool allow_inf,
                const char* unit, double* out, std::string* error) {
  const char* value = mj_getPluginConfig(m, instance, attr);
  const char* expected = allow_inf ? "a number >= 0 or inf" : "a finite number >= 0";
  if (value == nullptr || value[0] == '\0') {
    if (!required) return true;
    *error = std::string("attribute '") + attr + "' is missing: expected " + expected + " " + unit;
    return false;
  }
  char* end = nullptr;
  double number = std::strtod(value, &end);
  while (end && (*end == ' ' || *end == '\t')) end++;
  bool parsed = end != value && end && *end == '\0';
  if (!parsed || std::isnan(number) || number < 0 || (std::isinf(number) && !allow_inf)) {
    *error = std::string("attribute '") + attr + "' = '" + value + "': expected " + expected + " " +
             unit;
    return false;
  }
  *out = number;
  return true;
}

// parses "pos vel ff" (any subset, any order, spaces or commas) into a bitfield
bool ReadInput(const mjModel* m, int instance, int* input, std::string* error) {
  const char* value = mj_getPluginConfig(m, instance, kAttrInput);
  if (value == nullptr || value[0] == '\0') return true;
  std::string text(value);
  for (char& c : text) {
    if (c == ',') c = ' ';
  }
  int bits = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t stop = text.find(' ', start);
    if (stop == std::string::npos) stop = text.size();
    std::string word = text.substr(start, stop - start);
    start = stop + 1;
    if (word.empty()) continue;
    int bit = word == "pos" ? kInputPos : word == "vel" ? kInputVel : word == "ff" ? kInputFf : 0;
    if (!bit || (bits & bit)) {
      *error = std::string("attribute 'input' = '") + value +
               "': expected a subset of 'pos vel ff' without repeats";
      return false;
    }
    bits |= bit;
  }
  if (!bits) {
    *error = std::string("attribute 'input' = '") + value + "': expected at least one input";
    return false;
  }
  *input = bits;
  return true;
}

int InputCount(int input) {
  return !!(input & kInputPos) + !!(input & kInputVel) + !!(input & kInputFf);
}

std::string ActuatorName(const mjModel* m, int id) {
  const char* name = mj_id2name(m, mjOBJ_ACTUATOR, id);
  if (name && name[0]) return std::string("'") + name + "'";
  return "#" + std::to_string(id);
}

std::string JointName(const mjModel* m, int id) {
  const char* name = mj_id2name(m, mjOBJ_JOINT, id);
  if (name && name[0]) return std::string("'") + name + "'";
  return "#" + std::to_string(id);
}

// checks that actuator i can feed a drive; returns an empty string if it can
std::string CheckActuator(const mjModel* m, int i) {
  int trn = m->actuator_trntype[i];
  if (trn != mjTRN_JOINT && trn != mjTRN_JOINTINPARENT) {
    return "needs a joint transmission (a hinge or slide joint)";
  }
  int joint = m->actuator_trnid[2 * i];
  int type = m->jnt_type[joint];
  if (type != mjJNT_HINGE && type != mjJNT_SLIDE) {
    const char* kind = type == mjJNT_BALL ? "ball" : "free";
    return "joint " + JointName(m, joint) + " is a " + kind +
           " joint: expected a hinge or slide joint (one DOF)";
  }
  if (m->actuator_gear[6 * m->actuator_outadr[i]] != 1) {
    return "attribute 'gear' must be 1: the drive works on the joint side";
  }
  if (m->actuator_forcelimited[i]) {
    return "attribute 'forcerange' must not be set: the envelope limits the effort";
  }
  if (m->actuator_ctrlnum[i] != 1 || m->actuator_actnum[i] != 0) {
    return "expected one control and no activation (dyntype 'none', no actdim)";
  }
  return "";
}

// the dofs that L^-T * e_dof can reach, in descending order: dof, then every column of a reached
// row (its ancestors, plus any fill); fixed by the sparsity of M, so computed once per drive
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

}  // namespace

bool EnvelopeConfig::FromModel(const mjModel* m, int instance, EnvelopeConfig* config,
                               std::string* error) {
  EnvelopeConfig c;
  bool ok =
      ReadNumber(m, instance, kAttrStiffness, true, false, kUnitStiffness, &c.stiffness, error) &&
      ReadNumber(m, instance, kAttrDamping, true, false, kUnitDamping, &c.damping, error) &&
      ReadNumber(m, instance, kAttrMaxEffort, true, false, kUnitMaxEffort, &c.max_effort, error) &&
      ReadNumber(m, instance, kAttrMaxActuatorVelocity, false, true, kUnitVelocity,
                 &c.max_actuator_velocity, error) &&
      ReadNumber(m, instance, kAttrVelocityDependentResistance, false, false, kUnitResistance,
                 &c.velocity_dependent_resistance, error) &&
      ReadNumber(m, instance, kAttrSpeedEffortGradient, false, false, kUnitGradient,
                 &c.speed_effort_gradient, error) &&
      ReadInput(m, instance, &c.input, error);
  if (!ok) return false;
  const char* type = mj_getPluginConfig(m, instance, kAttrDriveType);
  if (type && type[0] && std::strcmp(type, "force") && std::strcmp(type, "acceleration")) {
    *error = std::string("attribute 'drive_type' = '") + type +
             "': expected 'force' or 'acceleration'";
    return false;
  }
  if (type && std::strcmp(type, "acceleration") == 0) c.drive_type = DriveType::kAcceleration;
  *config = c;
  return true;
}

std::unique_ptr<Envelope> Envelope::Create(const mjModel* m, int instance) {
  std::vector<int> actuators;
  for (int i = 0; i < m->nactuator; i++) {
    if (m->actuator_plugin[i] == instance) actuators.push_back(i);
  }
  if (actuators.empty()) {
    mju_warning("%s: plugin instance %d has no actuator", kPluginName, instance);
    return nullptr;
  }

  // configuration errors name the instance's first actuator
  EnvelopeConfig config;
  std::string error;
  if (!EnvelopeConfig::FromModel(m, instance, &config, &error)) {
    mju_warning("%s: actuator %s: %s", kPluginName, ActuatorName(m, actuators[0]).c_str(),
                error.c_str());
    return nullptr;
  }

  // group the actuators by joint, in order of appearance: one drive per joint
  std::vector<Drive> drives;
  std::vector<int> count;
  for (int i : actuators) {
    std::string problem = CheckActuator(m, i);
    if (!problem.empty()) {
      mju_warning("%s: actuator %s: %s", kPluginName, ActuatorName(m, i).c_str(),
                  problem.c_str());
      return nullptr;
    }
    int joint = m->actuator_trnid[2 * i];
    size_t k = 0;
    while (k < drives.size() && drives[k].joint != joint) k++;
    if (k == drives.size()) {
      Drive drive;
      drive.joint = joint;
      drive.dof = m->jnt_dofadr[joint];
      drive.qpos = m->jnt_qposadr[joint];
      drive.actuator = i;
      drive.chain = Chain(m, drive.dof);
      drives.push_back(drive);
      count.push_back(0);
    }
    drives[k].outputs.push_back(m->actuator_outadr[i]);
    count[k]++;
  }

  // the actuators of a joint feed the inputs in canonical order [pos, vel, ff]
  int ninput = InputCount(config.input);
  for (size_t k = 0; k < drives.size(); k++) {
    if (count[k] != ninput) {
      mju_warning("%s: actuator %s: joint %s has %d actuator(s) of this instance, expected %d "
                  "(one per input of attribute 'input')", kPluginName,
                  ActuatorName(m, drives[k].actuator).c_str(),
                  JointName(m, drives[k].joint).c_str(), count[k], ninput);
      return nullptr;
    }
    int slot = 0;
    for (int i : actuators) {
      if (m->actuator_trnid[2 * i] != drives[k].joint) continue;
      while (!(config.input & (1 << slot))) slot++;
      int adr = m->actuator_ctrladr[i];
      drives[k].ctrl[slot] = adr;
      drives[k].ctrllimited[slot] = m->actuator_ctrllimited[adr];
      drives[k].ctrlrange[slot][0] = m->actuator_ctrlrange[2 * adr];
      drives[k].ctrlrange[slot][1] = m->actuator_ctrlrange[2 * adr + 1];
      slot++;
    }
  }

  // the lowest instance of this plugin computes the shared acceleration for all of them
  int ourslot = -1;
  mjp_getPlugin(kPluginName, &ourslot);
  int leader = instance;
  for (int j = 0; j < m->nplugin; j++) {
    if (m->plugin[j] == ourslot) {
      leader = j;
      break;
    }
  }
  return std::unique_ptr<Envelope>(
      new Envelope(std::move(config), std::move(drives), leader, m->nv));
}

Envelope::Envelope(EnvelopeConfig config, std::vector<Drive> drives, int leader, int nv)
    : config_(std::move(config)), drives_(std::move(drives)), leader_(leader), force_(nv),
      qacc_(nv), chain_(nv, 0.0) {}

void Envelope::ComputeSmoothAcceleration(const mjModel* m, mjData* d) {
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
  mj_solveM(m, d, qacc_.data(), force, 1);
}

double Envelope::Response(const mjModel* m, const mjData* d, const Drive& drive) {
  // M = L'*D*L, so (M^-1)_ii = z'*D^-1*z with z = L^-T*e_i, nonzero only on the drive's chain
  mjtNum* z = chain_.data();
  z[drive.dof] = 1;
  double response = 0;
  for (int k : drive.chain) {
    mjtNum zk = z[k];
    z[k] = 0;  // leave the scratch zeroed for the next call
    response += zk * zk * d->qLDiagInv[k];
    int start = m->M_rowadr[k];
    int end = start + m->M_rownnz[k] - 1;
    for (int adr = start; adr < end; adr++) {
      z[m->M_colind[adr]] -= d->qLD[adr] * zk;
    }
  }
  return response;
}

void Envelope::Compute(const mjModel* m, mjData* d, int instance) {
  if (instance == leader_) ComputeSmoothAcceleration(m, d);
  const Envelope* leader = instance == leader_ ?
      this : reinterpret_cast<const Envelope*>(d->plugin_data[leader_]);
  const mjtNum* qacc = leader->qacc_.data();
  const EnvelopeConfig& c = config_;
  double dt = m->opt.timestep;

  for (const Drive& drive : drives_) {
    // inputs in canonical order; absent inputs are 0, limited ones are clamped
    double u[3] = {0, 0, 0};
    for (int s = 0; s < 3; s++) {
      if (drive.ctrl[s] < 0) continue;
      u[s] = d->ctrl[drive.ctrl[s]];
      if (drive.ctrllimited[s]) u[s] = mju_clip(u[s], drive.ctrlrange[s][0], drive.ctrlrange[s][1]);
    }
    double target_pos = u[0], target_vel = u[1], ff = u[2];

    // unconstrained end-of-step velocity before the drive, containing the feed-forward effort
    double r = Response(m, d, drive);
    double v0 = d->qvel[drive.dof] + dt * qacc[drive.dof] + dt * r * ff;

    // implicit PD effort, then the envelope clamp on the TOTAL actuator effort (drive + ff)
    double err = target_pos - d->qpos[drive.qpos];
    double effort = ff + ImplicitDriveEffort(c.stiffness, c.damping, err, v0, target_vel, r, dt,
                                             c.drive_type);
    double impulse = ClampDriveImpulse<double>(
        v0, ff * dt, effort * dt, r, c.max_actuator_velocity, c.max_effort * dt,
        c.speed_effort_gradient / dt, c.velocity_dependent_resistance * dt);

    // NaN or overflowing states: the drive lets go instead of writing NaN
    double total = 0;
    if (std::isfinite(impulse)) {
      // (x*dt)/dt can round one ulp above x: the clamp never grows a request, nor may we
      total = std::copysign(std::fmin(std::fabs(impulse / dt), std::fabs(effort)), impulse);
    }
    for (int out : drive.outputs) d->actuator_force[out] = 0;
    d->actuator_force[m->actuator_outadr[drive.actuator]] = total;
  }
}

void Envelope::RegisterPlugin() {
  mjpPlugin plugin;
  mjp_defaultPlugin(&plugin);
  plugin.name = kPluginName;
  plugin.capabilityflags |= mjPLUGIN_ACTUATOR;

  static const char* attributes[] = {
      kAttrStiffness, kAttrDamping, kAttrMaxEffort, kAttrMaxActuatorVelocity,
      kAttrVelocityDependentResistance, kAttrSpeedEffortGradient, kAttrDriveType, kAttrInput};
  plugin.nattribute = sizeof(attributes) / sizeof(attributes[0]);
  plugin.attributes = attributes;
  plugin.nstate = +[](const mjModel* m, int instance) { return 0; };

  plugin.init = +[](const mjModel* m, mjData* d, int instance) {
    std::unique_ptr<Envelope> envelope = Envelope::Create(m, instance);
    if (envelope == nullptr) return -1;
    d->plugin_data[instance] = reinterpret_cast<uintptr_t>(envelope.release());
    return 0;
  };
  plugin.destroy = +[](mjData* d, int instance) {
    delete reinterpret_cast<Envelope*>(d->plugin_data[instance]);
    d->plugin_data[instance] = 0;
  };
  plugin.reset = +[](const mjModel* m, mjtNum* plugin_state, void* plugin_data, int instance) {};
  plugin.compute = +[](const mjModel* m, mjData* d, int instance, int capability_bit) {
    reinterpret_cast<Envelope*>(d->plugin_data[instance])->Compute(m, d, instance);
  };
  mjp_registerPlugin(&plugin);
}

}  // namespace drive_envelope::mujoco_plugin
