"""Mobile manipulation: differential-drive base, task Jacobians, weighted least-norm redundancy
resolution and closed-loop task tracking (the loops run in Rust, one call per motion).

Units: m, rad, s. Wheel speeds are ordered (left, right) in rad/s; base poses are (x, y, θ);
the racket task "racket5" is seed 000's [centre x, y, z (m), polar, azimuth (rad)] of the racket
centre 0.15 m along the last z axis and of the face normal.

>>> import ttmanip
>>> base = ttmanip.DiffDrive(wheel_radius=0.075, track_width=0.42)
>>> [round(float(v), 6) for v in base.body_velocity([2.0, 6.0])]
[0.3, 0.714286]
"""

from __future__ import annotations

from ._ttmanip import DiffDrive, TrackResult, task_line, track, wls_step

__all__ = ["DiffDrive", "TrackResult", "task_line", "track", "wls_step"]
