"""A surface record: the channels a rig measures at the surface, in SI units, on one time axis, each sample
flagged usable or not (the contract between reading a record and estimating from it).

Channels (names inside the package; a file's columns are mapped to them by name or drilling mnemonic):

=======================  ============  ==========================================================
name                     unit          what
=======================  ============  ==========================================================
``top_speed``            rad/s         the top drive's (quill's) rotation speed
``surface_torque``       N·m           the torque the string takes from the top drive
``hook_load``            N             the load on the hook (the string's weight less the bit's)
``block_position``       m             the travelling block's height (decreasing as the bit drills)
``standpipe_pressure``   Pa            the mud pressure at the standpipe
=======================  ============  ==========================================================
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The surface channels and their SI units (pint spelling).
CHANNELS = {
    "top_speed": "rad/s",
    "surface_torque": "N*m",
    "hook_load": "N",
    "block_position": "m",
    "standpipe_pressure": "Pa",
}

#: Why a sample is not used (a flag's code -> its meaning); 0: usable.
FLAGS = {
    0: "usable",
    1: "missing (a gap in the record, or an empty or non-numeric cell)",
    2: "spike (an outlier against its neighbours)",
    3: "frozen (the channel repeats one value longer than its noise allows)",
    4: "out of range (a value the case cannot explain)",
}
USABLE, MISSING, SPIKE, FROZEN, OUT_OF_RANGE = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class SurfaceRecord:
    """Surface channels on one time axis.

    Attributes:
        time: sample times [s], strictly increasing (a record's own clock, from its first sample).
        channels: channel name (a key of :data:`CHANNELS`) -> values [SI] on ``time``; NaN where missing.
        flags: channel name -> int8 codes of :data:`FLAGS` on ``time``; a sample is used only where 0.
        source: where the record came from (a path, or a description), for messages.
        notes: what reading found and did (units converted, columns mapped, faults flagged), one line each.
    """

    time: np.ndarray
    channels: dict[str, np.ndarray]
    flags: dict[str, np.ndarray]
    source: str = ""
    notes: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self):
        t = np.asarray(self.time, dtype=float)
        if t.ndim != 1 or len(t) < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0.0):
            raise ValueError(f"{self.source or 'surface record'}: time must be at least 2 finite, strictly "
                             "increasing samples")
        for name, values in self.channels.items():
            if name not in CHANNELS:
                raise ValueError(f"{self.source or 'surface record'}: unknown channel {name!r}; channels are "
                                 f"{', '.join(CHANNELS)}")
            if np.shape(values) != t.shape or np.shape(self.flags.get(name, t)) != t.shape:
                raise ValueError(f"{self.source or 'surface record'}: channel {name!r} and its flags must have "
                                 f"one value per sample ({len(t)})")

    def usable(self, name: str) -> np.ndarray:
        """Boolean mask of the samples of channel ``name`` that an estimator may use."""
        return (np.asarray(self.flags[name]) == USABLE) & np.isfinite(self.channels[name])

    @classmethod
    def from_arrays(cls, time, source: str = "", **channels) -> SurfaceRecord:
        """A record from arrays in SI units, every finite sample usable (tests, synthetic records)."""
        values = {name: np.asarray(v, dtype=float) for name, v in channels.items()}
        flags = {name: np.where(np.isfinite(v), USABLE, MISSING).astype(np.int8) for name, v in values.items()}
        return cls(np.asarray(time, dtype=float), values, flags, source)
