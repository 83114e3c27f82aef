"""The foot-force sensors in newtons: each foot's ``counts = offset + gain x newtons``.

A GO2's ``foot_force`` is a raw count with no published unit, and its scale differs between
robots, firmwares and simulators (the project's simulated GO2 reads 10 + 2.5 counts per N,
one outside simulator 12 + 2.0, another 30 + 0.25). :class:`FootForceCalibration` holds
the model per foot (``LEGS`` order: FL, FR, RL, RR), given by name or learnt on the robot
with :class:`FootForceFit`: least squares of each foot's counts against a reference normal
force [N] while the load on that foot changes (a standing robot shifting its weight;
:mod:`actions.robot.foot_calibration` runs it). The estimators' contact thresholds are in
newtons (:class:`wbc.estimation.estimator_config.SensorTrustConfig`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.model.description import LEGS

#: Largest offset a foot's count can have (the message's int16).
_COUNT_LIMIT = 32767.0


def per_foot(name: str, value: Any, *, positive: bool = False) -> tuple[float, float, float,
                                                                      float]:
    """One number for every foot, four numbers (``LEGS`` order) or a ``{leg: number}`` map, as a
    tuple of four finite floats; ``positive`` also requires each to be above 0.

    Raises:
        ConfigurationError: Another shape, an unknown leg, a missing leg, or a bad number (the
            field, the leg and the value named).
    """
    if isinstance(value, Mapping):
        unknown = sorted(set(map(str, value)) - set(LEGS))
        missing = [leg for leg in LEGS if leg not in value]
        if unknown or missing:
            raise ConfigurationError(
                f"{name}: expected a number for each of {', '.join(LEGS)}, received "
                f"{dict(value)!r}" + (f" (unknown {unknown})" if unknown else "")
                + (f" (missing {missing})" if missing else ""))
        items = [value[leg] for leg in LEGS]
    elif isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        items = [value] * len(LEGS)
    elif isinstance(value, (Sequence, np.ndarray)) and not isinstance(value, str):
        items = list(value)
        if len(items) != len(LEGS):
            raise ConfigurationError(
                f"{name}: expected one number or {len(LEGS)} ({', '.join(LEGS)}), received "
                f"{len(items)}: {items!r}")
    else:
        raise ConfigurationError(
            f"{name}: expected one number, {len(LEGS)} numbers ({', '.join(LEGS)}) or a "
            f"{{leg: number}} map, received {value!r}")
    low = 0.0 if positive else -_COUNT_LIMIT
    return tuple(as_float(f"{name}[{leg}]", item, low=low, high=_COUNT_LIMIT,
                          low_inclusive=not positive)
                 for leg, item in zip(LEGS, items))  # type: ignore[return-value]


@dataclass(frozen=True)
class FootForceCalibration:
    """Each foot sensor's model, ``counts = offset + gain x normal force [N]``, ``LEGS`` order.

    Example::

        FootForceCalibration(offset=30.0, gain=0.25)                      # every foot
        FootForceCalibration(offset={"FL": 31, "FR": 29, "RL": 30, "RR": 30}, gain=0.25)

    Attributes:
        offset: Each foot's count with no load (one number: every foot's).
        gain: Its counts per newton, above 0.
        source: Where it comes from (``given``, ``default``, ``learnt ...``): shown at start.
    """

    offset: tuple[float, float, float, float] | float = 10.0
    gain: tuple[float, float, float, float] | float = 2.5
    source: str = "given"

    def __post_init__(self) -> None:
        object.__setattr__(self, "offset", per_foot("foot_force_offset", self.offset))
        object.__setattr__(self, "gain", per_foot("foot_force_gain", self.gain, positive=True))
        if not isinstance(self.source, str):
            raise ConfigurationError(f"source: expected text, received {self.source!r}")

    @property
    def offsets(self) -> np.ndarray:
        """The offsets [counts] (4,), ``LEGS`` order (a new array)."""
        return np.array(self.offset, dtype=float)

    @property
    def gains(self) -> np.ndarray:
        """The gains [counts/N] (4,), ``LEGS`` order (a new array)."""
        return np.array(self.gain, dtype=float)

    def newtons(self, counts: np.ndarray) -> np.ndarray:
        """Normal forces [N] from counts (..., 4), ``LEGS`` order."""
        return (np.asarray(counts, dtype=float) - self.offsets) / self.gains

    def counts(self, newtons: np.ndarray) -> np.ndarray:
        """Counts from normal forces [N] (..., 4), ``LEGS`` order."""
        return self.offsets + self.gains * np.asarray(newtons, dtype=float)

    def describe(self) -> str:
        """One line: each foot's offset and gain, and where they come from."""
        feet = ", ".join(f"{leg} {o:.4g} + {g:.4g}/N"
                         for leg, o, g in zip(LEGS, self.offset, self.gain))  # type: ignore
        return f"foot force [counts] = offset + gain x N ({self.source}): {feet}"

    def errors_against(self, truth: FootForceCalibration) -> tuple[float, float]:
        """The largest relative gain error and the largest offset error expressed in newtons
        (``|offset - true offset| / true gain``) against ``truth``."""
        gain = float(np.max(np.abs(self.gains / truth.gains - 1.0)))
        offset = float(np.max(np.abs(self.offsets - truth.offsets) / truth.gains))
        return gain, offset


class FootForceFit:
    """Learns :class:`FootForceCalibration` by least squares, one foot at a time.

    Each :meth:`add` is one sample: the four counts and a reference normal force [N] per foot
    (from the robot's weight and where its centre of mass is, for example). The sums are
    kept, not the samples, so a fit over any number of them costs nothing per sample. The
    offset and the gain of a foot are told apart only if its load changes: :meth:`result`
    refuses a fit whose loads spread less than ``min_spread_n``.

    Args:
        min_spread_n: Smallest standard deviation [N] of a foot's reference force that
            separates its gain from its offset.
        min_samples: Fewest samples of a fit.
    """

    def __init__(self, *, min_spread_n: float = 2.0, min_samples: int = 10):
        self.min_spread_n, self.min_samples = _fit_settings(min_spread_n, min_samples)
        self.clear()

    def clear(self) -> None:
        """Forget every sample."""
        self.samples = 0
        # Per foot, about the first sample (numerically steadier sums): n, sx, sy, sxx, sxy.
        self._origin: np.ndarray | None = None
        self._sums = np.zeros((5, len(LEGS)))

    def add(self, counts: np.ndarray, newtons: np.ndarray) -> None:
        """One sample: each foot's count and its reference normal force [N], ``LEGS`` order.

        Raises:
            ConfigurationError: Not four finite numbers each (the argument named).
        """
        y = np.asarray(counts, dtype=float)
        x = np.asarray(newtons, dtype=float)
        for name, value in (("counts", y), ("newtons", x)):
            if value.shape != (len(LEGS),) or not np.all(np.isfinite(value)):
                raise ConfigurationError(
                    f"{name}: expected {len(LEGS)} finite numbers ({', '.join(LEGS)}), "
                    f"received {value.tolist()!r}")
        if self._origin is None:
            self._origin = np.concatenate([x, y])
        dx, dy = x - self._origin[:4], y - self._origin[4:]
        sums = self._sums
        sums[0] += 1.0
        sums[1] += dx
        sums[2] += dy
        sums[3] += dx * dx
        sums[4] += dx * dy
        self.samples += 1

    def spread_n(self) -> np.ndarray:
        """Each foot's reference force's standard deviation over the samples [N] (4,)."""
        if self.samples == 0:
            return np.zeros(len(LEGS))
        n, sx, _, sxx, _ = self._sums
        return np.sqrt(np.maximum(sxx / n - (sx / n) ** 2, 0.0))

    def result(self, source: str = "learnt") -> FootForceCalibration:
        """The least-squares offset and gain of every foot.

        Raises:
            ConfigurationError: Too few samples, a foot whose load barely changed (its gain
                cannot be told from its offset: the loads named), or a gain that is not
                positive (the sensor does not follow the load: the foot named).
        """
        _check_fit_data(self.samples, self.min_samples, self.spread_n(), self.min_spread_n,
                        "shift the robot's weight while fitting")
        n, sx, sy, sxx, sxy = self._sums
        gain = (sxy / n - sx * sy / n ** 2) / (sxx / n - (sx / n) ** 2)
        bad = [f"{leg} {g:.3g}" for leg, g in zip(LEGS, gain) if not (g > 0 and math.isfinite(g))]
        if bad:
            raise ConfigurationError(
                f"foot-force fit: expected counts that grow with the load, received gains "
                f"{', '.join(bad)} counts/N (a sensor that does not follow its foot's load)")
        origin = self._origin if self._origin is not None else np.zeros(2 * len(LEGS))
        x0, y0 = origin[:4], origin[4:]
        offset = (y0 + sy / n) - gain * (x0 + sx / n)
        return FootForceCalibration(offset=tuple(offset), gain=tuple(gain), source=source)


class WeightShiftFit:
    """Learns :class:`FootForceCalibration` from a standing robot shifting its weight round a
    circle: each foot's counts against the load the weight puts on it there.

    Each :meth:`add` is one sample: the four counts, the feet's horizontal positions and the
    centre of pressure the rigid-body statics give (:func:`static_foot_loads`). A foot's
    load then moves with the centre of pressure's offset ``z`` from its mean,
    ``F_i = F_i(mean) + u_i . z``. On the realistic plant the true centre of pressure turns
    ahead of the rigid-body one by a few degrees round the circle (11 degrees on a 4.5 cm
    circle in 2 s: the legs share the load through their compliance and joint friction),
    which makes the rear feet's gains 7-10 % too high if left out; so the fit takes the
    turn ``phi`` as unknown too: each foot's counts are regressed on ``z`` (slopes ``s_i``),
    and ``s_i = g_i R(phi)^T u_i`` gives ``phi`` (a 2 x 2 eigenproblem) and each gain in
    closed form; the offsets follow from the means. The swing's size is the statics' (the
    feet cannot tell it from their gains), so the fit is exact when the plant follows them
    up to that turn.

    Args:
        weight_n: The robot's weight [N].
        min_spread_n: Smallest standard deviation [N] of a foot's load over the fit.
        min_samples: Fewest samples of a fit.
    """

    def __init__(self, weight_n: float, *, min_spread_n: float = 2.0, min_samples: int = 10):
        self.weight_n = as_float("weight_n", weight_n, low=0.0, high=1e5, low_inclusive=False)
        self.min_spread_n, self.min_samples = _fit_settings(min_spread_n, min_samples)
        self.samples = 0
        self.phase_deg = math.nan  # the last fit's turn of the centre of pressure
        self._feet = np.zeros((len(LEGS), 2))
        self._z = np.zeros(2)  # sums about the first sample
        self._zz = np.zeros((2, 2))
        self._c = np.zeros(len(LEGS))
        self._cz = np.zeros((len(LEGS), 2))
        self._origin: np.ndarray | None = None  # the first sample's centre of pressure, counts

    def add(self, counts: np.ndarray, feet_xy: np.ndarray, zmp_xy: np.ndarray) -> None:
        """One sample: each foot's count (``LEGS`` order), the feet's horizontal positions [m]
        (4, 2) and the rigid-body centre of pressure [m] (2,).

        Raises:
            ConfigurationError: A wrong shape or a non-finite number (the argument named).
        """
        c = np.asarray(counts, dtype=float)
        feet = np.asarray(feet_xy, dtype=float)
        z = np.asarray(zmp_xy, dtype=float)
        for name, value, shape in (("counts", c, (4,)), ("feet_xy", feet, (4, 2)),
                                   ("zmp_xy", z, (2,))):
            if value.shape != shape or not np.all(np.isfinite(value)):
                raise ConfigurationError(
                    f"{name}: expected finite numbers of shape {shape}, received "
                    f"{value.tolist()!r}")
        if self._origin is None:
            self._origin = np.concatenate([z, c])
        dz, dc = z - self._origin[:2], c - self._origin[2:]
        self._feet += feet
        self._z += dz
        self._zz += np.outer(dz, dz)
        self._c += dc
        self._cz += np.outer(dc, dz)
        self.samples += 1

    def _slopes(self) -> tuple[np.ndarray, np.ndarray]:
        """Each foot's load per metre of centre-of-pressure offset, by the statics (4, 2), and
        the feet's mean positions (4, 2)."""
        feet = self._feet / max(self.samples, 1)
        a = np.vstack([np.ones(len(LEGS)), feet[:, 0], feet[:, 1]])
        split = a.T @ np.linalg.inv(a @ a.T)
        return self.weight_n * split[:, 1:], feet

    def spread_n(self) -> np.ndarray:
        """Each foot's load's standard deviation over the samples [N] (4,), by the statics."""
        if self.samples == 0:
            return np.zeros(len(LEGS))
        n = self.samples
        cov = self._zz / n - np.outer(self._z / n, self._z / n)
        u, _ = self._slopes()
        return np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", u, cov, u), 0.0))

    def result(self, source: str = "learnt") -> FootForceCalibration:
        """Every foot's offset and gain (see the class docstring).

        Raises:
            ConfigurationError: Too few samples, loads that barely changed (named), a turn
                beyond 45 degrees or a gain that is not positive (the sensors do not follow
                the weight: the feet named).
        """
        _check_fit_data(self.samples, self.min_samples, self.spread_n(), self.min_spread_n,
                        "shift the robot's weight further")
        n = self.samples
        z_mean, c_mean = self._z / n, self._c / n
        cov = self._zz / n - np.outer(z_mean, z_mean)
        slopes = np.linalg.solve(cov, (self._cz / n - np.outer(c_mean, z_mean)).T).T  # (4, 2)
        u, feet = self._slopes()
        norm2 = np.sum(u * u, axis=1)
        along = np.sum(slopes * u, axis=1)
        across = slopes[:, 0] * u[:, 1] - slopes[:, 1] * u[:, 0]  # slopes . (u_y, -u_x)
        m = np.array([[np.sum(along ** 2 / norm2), np.sum(along * across / norm2)],
                      [np.sum(along * across / norm2), np.sum(across ** 2 / norm2)]])
        vector = np.linalg.eigh(m)[1][:, -1]
        if vector[0] < 0:
            vector = -vector
        phase = math.atan2(vector[1], vector[0])
        self.phase_deg = math.degrees(phase)
        gain = (along * math.cos(phase) + across * math.sin(phase)) / norm2
        if abs(self.phase_deg) > 45.0 or not np.all(gain > 0):
            raise ConfigurationError(
                f"foot-force fit: the counts do not follow the weight's shift (turned "
                f"{self.phase_deg:.0f} deg from the statics, gains "
                f"{', '.join(f'{leg} {g:.3g}' for leg, g in zip(LEGS, gain))} counts/N): "
                "check the feet's order and that every sensor reads its foot")
        origin = self._origin if self._origin is not None else np.zeros(2 + len(LEGS))
        mean_loads = static_foot_loads(feet, origin[:2] + z_mean, self.weight_n)
        offset = origin[2:] + c_mean - gain * mean_loads
        return FootForceCalibration(offset=tuple(offset), gain=tuple(gain), source=source)


def _fit_settings(min_spread_n: float, min_samples: int) -> tuple[float, int]:
    """A fit's least load spread [N] and fewest samples, checked (the field named)."""
    spread = as_float("min_spread_n", min_spread_n, low=0.0, high=1e4, low_inclusive=False)
    if isinstance(min_samples, bool) or not isinstance(min_samples, int) or min_samples < 3:
        raise ConfigurationError(
            f"min_samples: expected a whole number >= 3, received {min_samples!r}")
    return spread, min_samples


def _check_fit_data(samples: int, min_samples: int, spread_n: np.ndarray,
                    min_spread_n: float, hint: str) -> None:
    """Refuse a fit on too few samples or on a foot whose load barely changed (its gain cannot
    be told from its offset), naming the loads and what to do (``hint``)."""
    if samples < min_samples:
        raise ConfigurationError(
            f"foot-force fit: expected at least {min_samples} samples, received {samples}")
    flat = [f"{leg} {s:.2g} N" for leg, s in zip(LEGS, spread_n) if s < min_spread_n]
    if flat:
        raise ConfigurationError(
            f"foot-force fit: the load on a foot must change by at least {min_spread_n:g} N "
            f"(standard deviation) to tell its gain from its offset; received "
            f"{', '.join(flat)}: {hint}")


def static_foot_loads(feet_xy: np.ndarray, zmp_xy: np.ndarray, weight_n: float) -> np.ndarray:
    """Each foot's normal force [N] (4,) carrying ``weight_n`` with the centre of pressure at
    ``zmp_xy`` [m]: the smallest forces (least squares) with that sum and those moments.

    Four feet carry a weight in many ways; the smallest-forces split is the one the
    controller's QP asks for (it regularises the forces), and a standing robot's feet share
    it to within a few newtons (``docs/state-estimation.md``, measured).

    Args:
        feet_xy: The feet's horizontal positions [m] (4, 2), ``LEGS`` order.
        zmp_xy: The centre of pressure [m] (2,): the centre of mass's, less ``h / g`` times
            its horizontal acceleration.
        weight_n: The weight [N].
    """
    a = np.vstack([np.ones(len(LEGS)), feet_xy[:, 0], feet_xy[:, 1]])
    b = weight_n * np.array([1.0, zmp_xy[0], zmp_xy[1]])
    return a.T @ np.linalg.solve(a @ a.T, b)
