"""System identification from bench logs: the envelope, drive, friction and armature a bench implies.

``identify(["log1.csv", "log2.csv"], "stand.toml", validate=["held_out.csv"], fit=[...])`` replays
each log's targets through the reference test stand (the PhysX solver model) and searches the
fitted parameters that make the simulated positions match the measured ones: SciPy's differential
evolution over batched replays (a whole population per NumPy pass), then a least-squares polish.
It returns an :class:`Identification`: every parameter with its value, standard deviation and
whether it was fixed, the identified envelope and stand scenario, and each log's mean absolute
position error (also in PhysX or MuJoCo with ``engine=``). :func:`identification_to_dict` gives the
``--json`` object and :func:`save_identification_figure` the figure.

The search runs ``restarts`` times (each parameter's ``spread`` over them is its seed
uncertainty) and reports the envelope in canonical form (a line that never binds is moved to where
it binds, with a note). :func:`save_stand` writes the identified stand (``result.stand``) and
:func:`replay_logs` replays logs through a stand file (``drive-envelope replay``).

Logs: :func:`read_bench_log` (CSV, Parquet or a ROS 2 bag: ``time``, ``position``,
``target_position``, optional ``velocity``, ``effort``, ``target_velocity``, ``torque_enable``).
The stand file is a scenario with a ``[pendulum]`` table and the optional ``[servo]`` and ``[bounds]`` tables
(:func:`read_stand`). SI throughout. Needs SciPy (``pip install 'drive-envelope[identify]'``),
imported when the search runs; the figure needs matplotlib.
"""

from __future__ import annotations

from drive_envelope._src.identify.logs import BenchLog, read_bench_log
from drive_envelope._src.identify.optimize import SearchOptions, SearchProgress, SearchResult
from drive_envelope._src.identify.parameters import DEFAULT_FIT, IDENTIFIABLE
from drive_envelope._src.identify.playback import Playback, replay_logs
from drive_envelope._src.identify.report import identification_text, identification_to_dict
from drive_envelope._src.identify.run import Estimate, Identification, LogError, identify
from drive_envelope._src.identify.stand import IdentifyStand, read_stand
from drive_envelope._src.identify.stand_file import save_stand
from drive_envelope._src.plots.identification import identification_figure, save_identification_figure

__all__ = [
    "DEFAULT_FIT",
    "IDENTIFIABLE",
    "BenchLog",
    "Estimate",
    "Identification",
    "IdentifyStand",
    "LogError",
    "Playback",
    "SearchOptions",
    "SearchProgress",
    "SearchResult",
    "identification_figure",
    "identification_text",
    "identification_to_dict",
    "identify",
    "read_bench_log",
    "read_stand",
    "replay_logs",
    "save_identification_figure",
    "save_stand",
]
