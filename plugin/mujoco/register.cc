// Copyright 2026 The drive-envelope authors. BSD-3-Clause.

#include <mujoco/mjplugin.h>
#include <mujoco/mujoco.h>

#include "envelope.h"

namespace drive_envelope::mujoco_plugin {

// register only against the MuJoCo this library was compiled for: the plugin reads mjModel and
// mjData fields directly, so another version's layout would be read as garbage
mjPLUGIN_LIB_INIT(drive_envelope) {
  if (mj_version() != mjVERSION_HEADER) {
    mju_warning("drive_envelope.envelope: built for MuJoCo %d but loaded into MuJoCo %d; "
                "rebuild it with `python -m drive_envelope._src.adapters.mujoco.build`",
                mjVERSION_HEADER, mj_version());
    return;
  }
  Envelope::RegisterPlugin();
}

}  // namespace drive_envelope::mujoco_plugin
