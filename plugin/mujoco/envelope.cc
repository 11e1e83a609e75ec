// Copyright 2026 The drive-envelope authors. BSD-3-Clause.

#include "envelope.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

#include "coupled.h"

namespace drive_envelope::mujoco_plugin {
namespace {

constexpr char kPluginName[] = "drive_envelope.envelope";
constexpr char kAttrDriveType[] = "drive_type";
constexpr char kAttrInput[] = "input";

constexpr const char* kSlotNames[kNumSlots] = {
    "max_effort", "max_actuator_velocity", "velocity_dependent_resistance",
    "speed_effort_gradient", "stiffness", "damping"};

constexpr const char* kSlotUnits[kNumSlots] = {
    "[N*m or N]", "[rad/s or m/s]", "[N*m*s/rad or N*s/m]", "[(rad/s)/(N*m) or (m/s)/N]",
    "[N*m/rad or N/m; 1/s^2 for an acceleration drive]",
    "[N*m*s/rad or N*s/m; 1/s for an acceleration drive]"};

constexpr char kLayout[] = "dynprm = \"max_effort max_actuator_velocity "
                           "velocity_dependent_resistance speed_effort_gradient stiffness damping\"";

// the shortest text that reads back as value (15 digits if they round-trip, else 17)
std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.15g", value);
  if (std::strtod(text, nullptr) != value && !std::isnan(value)) {
    std::snprintf(text, sizeof(text), "%.17g", value);
  }
  return text;
}

// parses "pos vel ff" (any subset, any order, spaces or commas) into a bitfield
bool ReadInput(const mjModel* m, int instance, int* input, std::string* error) {
  const char* value = mj_getPluginConfig(m, instance, kAttrInput);
  if (value == nullptr || value[0] == '\0') return true;
  std::string text(value);
  for (char& c : text) {
    if (c == ',' || c == '\t') c = ' ';
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
  if (m->actuator_ctrlnum[i] != 1 || m->actuator_actnum[i] != 0 ||
      m->actuator_dyntype[i] != mjDYN_NONE) {
    return "expected one control and no activation (dyntype 'none', no actdim)";
  }
  return "";
}

// MuJoCo's default dynprm (1 0 0 ...): the drive's numbers were never given
bool IsDefaultDynprm(const mjModel* m, int i) {
  const mjtNum* prm = m->actuator_dynprm + mjNDYN * i;
  if (prm[0] != 1) return false;
  for (int k = 1; k < mjNDYN; k++) {
    if (prm[k] != 0) return false;
  }
  return true;
}

// the drives of one instance, its actuators grouped by joint in order of appearance
bool InstanceDrives(const mjModel* m, int instance, std::vector<Drive>* drives,
                    std::string* error) {
  std::vector<int> actuators;
  for (int i = 0; i < m->nactuator; i++) {
    if (m->actuator_plugin[i] == instance) actuators.push_back(i);
  }
  if (actuators.empty()) {
    *error = "plugin instance #" + std::to_string(instance) + " has no actuator";
    return false;
  }
  InstanceConfig config;
  std::string problem;
  if (!InstanceConfig::FromModel(m, instance, &config, &problem)) {
    *error = "actuator " + ActuatorName(m, actuators[0]) + ": " + problem;
    return false;
  }
  std::vector<Drive> found;
  for (int i : actuators) {
    problem = CheckActuator(m, i);
    if (!problem.empty()) {
      *error = "actuator " + ActuatorName(m, i) + ": " + problem;
      return false;
    }
    int joint = m->actuator_trnid[2 * i];
    size_t k = 0;
    while (k < found.size() && found[k].joint != joint) k++;
    if (k == found.size()) {
      Drive drive;
      drive.joint = joint;
      drive.dof = m->jnt_dofadr[joint];
      drive.qpos = m->jnt_qposadr[joint];
      drive.actuator = i;
      drive.drive_type = config.drive_type;
      found.push_back(drive);
    }
    found[k].actuators.push_back(i);
  }

  // the actuators of a joint feed the inputs in canonical order [pos, vel, ff]
  int ninput = InputCount(config.input);
  for (Drive& drive : found) {
    int count = static_cast<int>(drive.actuators.size());
    if (count != ninput) {
      *error = "actuator " + ActuatorName(m, drive.actuator) + ": joint " +
               JointName(m, drive.joint) + " has " + std::to_string(count) +
               " actuator(s) of this instance, expected " + std::to_string(ninput) +
               " (one per input of attribute 'input')";
      return false;
    }
    int slot = 0;
    for (int i : drive.actuators) {
      while (!(config.input & (1 << slot))) slot++;
      drive.input[slot++] = i;
    }
  }
  drives->insert(drives->end(), found.begin(), found.end());
  return true;
}

// other actuators that push a driven joint bypass the envelope: say so once, naming both
void WarnOtherActuators(const mjModel* m, const Structure& s) {
  for (const Drive& drive : s.drives) {
    for (int i : s.native) {
      bool on_joint = (m->actuator_trntype[i] == mjTRN_JOINT ||
                       m->actuator_trntype[i] == mjTRN_JOINTINPARENT) &&
                      m->actuator_trnid[2 * i] == drive.joint;
      bool on_tendon = false;
      if (m->actuator_trntype[i] == mjTRN_TENDON) {
        int tendon = m->actuator_trnid[2 * i];
        for (int w = m->tendon_adr[tendon]; w < m->tendon_adr[tendon] + m->tendon_num[tendon];
             w++) {
          on_tendon |= m->wrap_type[w] == mjWRAP_JOINT && m->wrap_objid[w] == drive.joint;
        }
      }
      if (on_joint || on_tendon) {
        WarnOnce(std::string(kPluginName) + ": actuator " + ActuatorName(m, i) +
                 " also acts on joint " + JointName(m, drive.joint) + ", driven by " +
                 ActuatorName(m, drive.actuator) +
                 ": its force bypasses the envelope (the drive's 'ff' input adds effort that "
                 "counts)");
      }
    }
    if (m->jnt_actfrclimited[drive.joint]) {
      // a range at or beyond max_effort cannot bind: the envelope bounds the total effort first
      const mjtNum* range = m->jnt_actfrcrange + 2 * drive.joint;
      double tightest = std::min(std::fabs(range[0]), std::fabs(range[1]));
      DriveParams params;
      std::string ignored;
      bool read = DriveParams::FromModel(m, drive.actuator, &params, &ignored) < 0;
      if (!read || tightest < params.max_effort) {
        WarnOnce(std::string(kPluginName) + ": joint " + JointName(m, drive.joint) +
                 " has an actuatorfrcrange below the drive's max_effort: MuJoCo clips the "
                 "drive's effort after the envelope");
      }
    }
  }
}

std::mutex warn_mutex;

}  // namespace

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

void WarnOnce(const std::string& message) {
  // leaked on purpose: no destruction-order issue at exit
  static std::set<std::string>* seen = new std::set<std::string>();
  {
    std::lock_guard<std::mutex> lock(warn_mutex);
    if (!seen->insert(message).second) return;
  }
  mju_warning("%s", message.c_str());
}

int LeaderInstance(const mjModel* m) {
  int slot = -1;
  mjp_getPlugin(kPluginName, &slot);
  for (int j = 0; j < m->nplugin; j++) {
    if (m->plugin[j] == slot) return j;
  }
  return -1;
}

int DriveParams::FromModel(const mjModel* m, int i, DriveParams* params, std::string* error) {
  const mjtNum* prm = m->actuator_dynprm + mjNDYN * i;
  double value[kNumSlots];
  for (int s = 0; s < kNumSlots; s++) {
    bool no_limit = s <= kSlotMaxActuatorVelocity && prm[s] == kNoLimit;
    if (!no_limit && !(prm[s] >= 0 && prm[s] <= kParamBound)) {
      *error = "dynprm[" + std::to_string(s) + "] (" + kSlotNames[s] + ") = " + Number(prm[s]) +
               ": expected a number in [0, 1e12]" +
               (s <= kSlotMaxActuatorVelocity ? " or -1 (no limit) " : " ") + kSlotUnits[s];
      return s;
    }
    value[s] = no_limit ? INFINITY : prm[s];
  }
  for (int s = kNumSlots; s < mjNDYN; s++) {
    if (prm[s] != 0) {
      *error = "dynprm[" + std::to_string(s) + "] = " + Number(prm[s]) + ": reserved, expected 0";
      return s;
    }
  }
  params->max_effort = value[kSlotMaxEffort];
  params->max_actuator_velocity = value[kSlotMaxActuatorVelocity];
  params->velocity_dependent_resistance = value[kSlotResistance];
  params->speed_effort_gradient = value[kSlotGradient];
  params->stiffness = value[kSlotStiffness];
  params->damping = value[kSlotDamping];
  return -1;
}

bool SolverSetting::FromModel(const mjModel* m, int id, SolverSetting* setting,
                              std::string* error) {
  SolverSetting out;
  if (id < 0) {
    *setting = out;
    return true;
  }
  int size = m->numeric_size[id];
  const mjtNum* value = m->numeric_data + m->numeric_adr[id];
  // read at every step: the message's text is built only for an error (no allocation otherwise)
  auto where = [] { return std::string("custom numeric '") + kSolverNumeric + "'"; };
  if (size != 3 && size != 4) {
    *error = where() + " has " + std::to_string(size) +
             " number(s): expected 'solver position_iterations velocity_iterations [constraints]' "
             "(solver 0 exact, 1 pgs, 2 tgs)";
    return false;
  }
  double kind = value[0], position = value[1], velocity = value[2];
  if (!(kind == 0 || kind == 1 || kind == 2)) {
    *error = where() + "[0] (solver) = " + Number(kind) + ": expected 0 (exact), 1 (pgs) or 2 (tgs)";
    return false;
  }
  if (!(position >= 1 && position <= kMaxIterations && position == std::floor(position))) {
    *error = where() + "[1] (position_iterations) = " + Number(position) +
             ": expected an integer in [1, 255]";
    return false;
  }
  if (!(velocity >= 0 && velocity <= kMaxIterations && velocity == std::floor(velocity))) {
    *error = where() + "[2] (velocity_iterations) = " + Number(velocity) +
             ": expected an integer in [0, 255]";
    return false;
  }
  double constraints = size == 4 ? value[3] : 0;
  if (!(constraints == 0 || constraints == 1)) {
    *error = where() + "[3] (constraints) = " + Number(constraints) +
             ": expected 0 (drives solved before MuJoCo's constraints) or 1 (with them)";
    return false;
  }
  if (constraints == 1 && kind != 0) {
    // PhysX's PGS/TGS iterate the drives against the articulation alone: no rule to port
    *error = where() + "[3] (constraints) = 1 with solver " + Number(kind) +
             ": expected solver 0 (exact); pgs and tgs solve the drives before the constraints";
    return false;
  }
  out.kind = static_cast<SolverKind>(static_cast<int>(kind));
  out.position_iterations = static_cast<int>(position);
  out.velocity_iterations = static_cast<int>(velocity);
  out.constraints = constraints == 1;
  *setting = out;
  return true;
}

bool InstanceConfig::FromModel(const mjModel* m, int instance, InstanceConfig* config,
                               std::string* error) {
  InstanceConfig c;
  if (!ReadInput(m, instance, &c.input, error)) {
    return false;
  }
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

bool Structure::Build(const mjModel* m, Structure* structure, std::string* error) {
  int slot = -1;
  mjp_getPlugin(kPluginName, &slot);
  Structure s;
  for (int j = 0; j < m->nplugin; j++) {
    if (m->plugin[j] == slot && !InstanceDrives(m, j, &s.drives, error)) return false;
  }

  // one drive per joint, whatever the instance: two would add up past the envelope
  for (size_t a = 0; a < s.drives.size(); a++) {
    for (size_t b = a + 1; b < s.drives.size(); b++) {
      if (s.drives[a].joint == s.drives[b].joint) {
        *error = "joint " + JointName(m, s.drives[a].joint) + " has two drives: actuators " +
                 ActuatorName(m, s.drives[a].actuator) + " and " +
                 ActuatorName(m, s.drives[b].actuator) +
                 " (one drive per joint; its 'ff' input adds effort that counts)";
        return false;
      }
    }
  }

  // every drive's numbers must be valid when the data is made
  for (const Drive& drive : s.drives) {
    std::string problem;
    if (IsDefaultDynprm(m, drive.actuator)) {
      *error = "actuator " + ActuatorName(m, drive.actuator) +
               ": dynprm is MuJoCo's default (1 0 0 0 0 0): give the drive's numbers, " + kLayout +
               " (-1: no limit)";
      return false;
    }
    DriveParams params;
    if (DriveParams::FromModel(m, drive.actuator, &params, &problem) >= 0) {
      *error = "actuator " + ActuatorName(m, drive.actuator) + ": " + problem;
      return false;
    }
  }
  if (!(m->opt.timestep > 0 && std::isfinite(m->opt.timestep))) {
    *error = "option 'timestep' = " + Number(m->opt.timestep) +
             ": expected a finite number > 0 [s]";
    return false;
  }

  s.solver_numeric = mj_name2id(m, mjOBJ_NUMERIC, kSolverNumeric);
  SolverSetting setting;
  if (!SolverSetting::FromModel(m, s.solver_numeric, &setting, error)) return false;

  std::sort(s.drives.begin(), s.drives.end(),
            [](const Drive& a, const Drive& b) { return a.dof < b.dof; });
  for (int i = 0; i < m->nactuator; i++) {
    int instance = m->actuator_plugin[i];
    if (instance < 0 || m->plugin[instance] != slot) s.native.push_back(i);
  }
  *structure = std::move(s);
  return true;
}

std::unique_ptr<Envelope> Envelope::Create(const mjModel* m, mjData* d, int instance) {
  if (instance != LeaderInstance(m)) {
    return std::unique_ptr<Envelope>(new Envelope(nullptr));  // the leader does the work
  }
  Structure structure;
  std::string error;
  if (!Structure::Build(m, &structure, &error)) {
    mju_warning("%s: %s", kPluginName, error.c_str());
    return nullptr;
  }
  WarnOtherActuators(m, structure);
  auto solver = std::make_unique<CoupledSolver>(m, std::move(structure));
  return std::unique_ptr<Envelope>(new Envelope(std::move(solver)));
}

Envelope::Envelope(std::unique_ptr<CoupledSolver> solver) : solver_(std::move(solver)) {}

Envelope::~Envelope() = default;

void Envelope::Compute(const mjModel* m, mjData* d, int instance) {
  if (!solver_) return;
  last_iterations_ = solver_->Compute(m, d);
  last_solves_ = solver_->solves();
  last_constraint_solves_ = solver_->constraint_solves();
}

void Envelope::Advance(const mjModel* m, mjData* d) {
  if (solver_) solver_->Advance(m, d);
}

void Envelope::RegisterPlugin() {
  mjpPlugin plugin;
  mjp_defaultPlugin(&plugin);
  plugin.name = kPluginName;
  plugin.capabilityflags |= mjPLUGIN_ACTUATOR;

  static const char* attributes[] = {kAttrDriveType, kAttrInput};
  plugin.nattribute = sizeof(attributes) / sizeof(attributes[0]);
  plugin.attributes = attributes;

  // no state: the drives are a function of (qpos, qvel, ctrl, the model); diagnostics live in the
  // instance (drive_envelope_solver_stats), so a saved mjSTATE_FULLPHYSICS restores the physics alone
  plugin.nstate = +[](const mjModel* m, int instance) { return 0; };
  plugin.init = +[](const mjModel* m, mjData* d, int instance) {
    std::unique_ptr<Envelope> envelope = Envelope::Create(m, d, instance);
    if (envelope == nullptr) return -1;
    d->plugin_data[instance] = reinterpret_cast<uintptr_t>(envelope.release());
    return 0;
  };
  plugin.destroy = +[](mjData* d, int instance) {
    delete reinterpret_cast<Envelope*>(d->plugin_data[instance]);
    d->plugin_data[instance] = 0;
  };
  plugin.reset = +[](const mjModel* m, mjtNum* plugin_state, void* plugin_data, int instance) {
    if (plugin_data != nullptr) reinterpret_cast<Envelope*>(plugin_data)->ResetStats();
  };
  plugin.compute = +[](const mjModel* m, mjData* d, int instance, int capability_bit) {
    reinterpret_cast<Envelope*>(d->plugin_data[instance])->Compute(m, d, instance);
  };
  plugin.advance = +[](const mjModel* m, mjData* d, int instance) {
    reinterpret_cast<Envelope*>(d->plugin_data[instance])->Advance(m, d);
  };
  mjp_registerPlugin(&plugin);
}

}  // namespace drive_envelope::mujoco_plugin
