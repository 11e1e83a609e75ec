"""Isaac Lab adapter: the envelope as an Isaac Lab actuator, an event term, and the implicit path.

``actuator`` defines ``PerformanceEnvelopeActuatorCfg`` / ``PerformanceEnvelopeActuator`` (subclasses
of Isaac Lab's ``IdealPDActuatorCfg`` / ``IdealPDActuator``, built on first use); ``events`` the
``randomize_actuator_envelope`` event term; ``implicit`` authors the envelope in the robot's USD
for PhysX's own drive with the matching ``ImplicitActuatorCfg``; ``tensor_api`` writes it at run
time in the PhysX tensor API's order. Isaac Lab (``isaaclab.actuators``, ``isaaclab.utils``) and
torch are imported inside functions only; the public entry point is :mod:`drive_envelope.isaaclab`.
"""
