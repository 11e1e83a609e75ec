"""MuJoCo Warp (MJWarp) adapter: the MuJoCo plugin's coupled envelope drive as Warp kernels.

MJWarp's ``put_model`` refuses actuator plugins, so the same MJCF that runs in C MuJoCo with
``drive_envelope.envelope`` actuators goes to MJWarp through :func:`.model.put_model`: a copy of
its spec with the plugin actuators turned into plain actuators (same names, controls and
``dynprm``), whose forces an ``act_bias`` callback then writes with the plugin's law, solved over
(nworld, drives) on the device. Modules here import ``mujoco_warp`` and ``warp`` only inside
functions, except :mod:`.kernels` and :mod:`.solve`, which define Warp code at module level and
are themselves imported lazily.
"""
