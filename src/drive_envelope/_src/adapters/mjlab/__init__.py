"""mjlab adapter: mjlab actuators (Isaac Lab's API on MJWarp) whose effort is limited by the envelope.

:mod:`.actuator` imports mjlab and torch at the top (its classes subclass mjlab's), so only the
public facade ``drive_envelope.mjlab`` imports it, lazily. It depends on no MuJoCo version: mjlab
1.6 pins MuJoCo 3.11, the ``drive_envelope.envelope`` plugin is built for MuJoCo 4, and neither
the explicit law (torch) nor the implicit one (the MJWarp drive kernels on a plugin-free model)
needs the plugin.
"""
