"""Isaac Lab adapter: the envelope as an Isaac Lab actuator, an event term, and the implicit path.

``actuator_classes`` defines ``PerformanceEnvelopeActuatorCfg`` / ``PerformanceEnvelopeActuator``
(subclasses of Isaac Lab's ``IdealPDActuatorCfg`` / ``IdealPDActuator``) and imports Isaac Lab and
torch at its top, so it is loaded on first use; ``actuator`` reads the cfg's values; ``events`` holds
the ``randomize_actuator_envelope`` event term and ``set_response_from_mass_matrix``; ``implicit``
authors the envelope in the robot's USD for PhysX's own drive with the matching
``ImplicitActuatorCfg``; ``tensor_api`` writes it at run time in the PhysX tensor API's order.
Elsewhere Isaac Lab (``isaaclab.actuators``, ``isaaclab.utils``) and torch are imported inside
functions only; the public entry point is :mod:`drive_envelope.isaaclab`.
"""
