"""Batched backends of the envelope, pure math per library (no engine objects).

``warp_funcs`` holds the Warp ``@wp.func`` building blocks and kernels and imports Warp at the top;
``warp_ops`` (its launch wrappers, :class:`EnvelopeArrays`), ``torch_envelope``
(:class:`EnvelopeTensors`) and ``torch_ops`` import their library on first use, so the public
facades stay light. ``envelope_values`` reads and validates user values for both.
"""
