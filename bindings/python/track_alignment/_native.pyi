"""Type hints of the Rust extension (bindings/src)."""

from os import PathLike
from typing import Any, Mapping, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
Setting = bool | int | float | str

def estimate(
    speed: ArrayLike,
    ws_acc_y: ArrayLike,
    ws_yaw_rate: ArrayLike,
    frame_acc_y: ArrayLike,
    *,
    step: float,
    ws_roll_rate: ArrayLike | None = None,
    design_curvature: ArrayLike | None = None,
    design_cant: ArrayLike | None = None,
    settings: Mapping[str, Setting] | None = None,
    calibration: str | PathLike[str] | None = None,
    smooth: bool = False,
    check_covariance: bool = False,
    resume: EstimatorState | None = None,
) -> dict[str, Any]:
    """The estimator FMU stepped every ``step`` seconds over these samples (sample ``k`` holds
    the speed [m/s] and sensors [m/s2, rad/s] at the end of step ``k``).

    ``settings`` are FMU parameters by name (``{"estimator": 1, "lag": 5.0}``);
    ``calibration`` another calibration file; ``smooth`` adds the Rauch-Tung-Striebel smoother,
    run on the filter that ran: with the learned filter (``estimator`` 2, the default) its Kalman
    channel, whose gain is the scheduled steady-state one unless ``gain`` is 1.
    Float64 contiguous arrays are read in place; other array-likes are converted once.

    Returns the FMU's outputs per sample as float64 arrays: ``alignment``, ``alignment_std``,
    ``alignment_lagged``, ``alignment_lagged_std``, ``distance_lagged``, ``alignment_kalman``,
    ``contact_scale``, ``distance`` [m]; ``active_estimator`` (int32); with ``smooth``,
    ``alignment_smoothed`` and ``alignment_smoothed_std``; and ``skipped_updates`` (int).

    Without ``smooth``, also ``state``: where the run stopped. Passed as ``resume`` to a call
    with the same settings, calibration and step, the run continues as if the samples had come
    in one call (bit-equal outputs). ``check_covariance`` adds ``covariance``: the Kalman
    filter's P after every filter step, ``{steps, min_eigenvalue, min_relative, max_asymmetry}``
    (an eigen-decomposition per step: for soak tests).
    """

class EstimatorState:
    """Where a call of :func:`estimate` stopped (opaque; pass it as ``resume``)."""

def parameters() -> dict[str, tuple[str, Setting, str]]:
    """``{name: (FMI type, default, description)}`` of every estimator parameter."""

BANDS: list[tuple[str, tuple[float, float]]]
"""The metric's bands, (name, (shortest, longest wavelength in m)): whole, D1, D2, D3."""

def band_metrics(
    estimate_distance: ArrayLike,
    estimate: ArrayLike,
    truth_distance: ArrayLike,
    truth: ArrayLike,
    *,
    ds: float = 0.05,
    trim: float = 10.0,
) -> dict[str, dict[str, float]]:
    """Per band (``whole`` 3-200 m, ``D1`` 3-25, ``D2`` 25-70, ``D3`` 70-200):
    ``{"J_mm", "Jrel", "truth_rms_mm"}``, the studies' metric (docs/studies.md)."""

def bandpass(x: ArrayLike, ds: float, short: float, long: float) -> npt.NDArray[np.float64]:
    """``x`` (every ``ds`` m) through the metrics' zero-phase Butterworth band-pass between
    wavelengths ``short`` and ``long`` [m]."""

def simulate(
    fmu: str | PathLike[str],
    stop_time: float,
    *,
    step: float = 1e-3,
    parameters: Mapping[str, Setting] | None = None,
    variables: Sequence[str] | None = None,
) -> dict[str, npt.NDArray[np.float64]]:
    """One FMU run by the co-simulation master from 0 to ``stop_time``: ``{"time", variable...}``
    for ``variables`` (default: every output)."""

def fit(
    out: str | PathLike[str],
    *,
    vehicle: str | PathLike[str] | None = None,
    estimator: str | PathLike[str] | None = None,
    vehicle_settings: Mapping[str, Setting] | None = None,
    recordings: Sequence[str | PathLike[str]] | None = None,
    reference: str | PathLike[str] | None = None,
    speeds: Sequence[float] | None = None,
    kalker_scales: Sequence[float] | None = None,
    conicities: Sequence[float] | None = None,
    lags: Sequence[float] | None = None,
    roll_rate: bool = True,
    seed: int | None = None,
    validation_seeds: Sequence[int] | None = None,
    evaluation_seeds: Sequence[int] | None = None,
    validation_share: float | None = None,
    calibration: str | PathLike[str] | None = None,
) -> str:
    """``alignment-studies fit`` (docs/studies.md): the estimator fitted to the vehicle FMU
    ``vehicle`` (with ``vehicle_settings``, its parameters), or to ``recordings`` of an
    instrumented train against the line's ``reference`` alignment, written into the new
    directory ``out`` (``fitted.taps``, ``report.md``; from the FMU also ``fitted-calibration.toml``
    and ``model_adjustment.svg``). The options are the command's, checked by its parser; bad
    input raises ``ValueError`` naming the file or option, and leaves nothing at ``out``.
    Returns the report (Markdown)."""

def fit_design(
    speed: ArrayLike,
    ws_yaw_rate: ArrayLike,
    ws_roll_rate: ArrayLike,
    ws_acc_y: ArrayLike,
    *,
    step: float,
    rounding: float = 10.0,
    half_gauge: float | None = None,
    gravity: float | None = None,
    design_response_file: str | None = None,
) -> dict[str, Any]:
    """The design line of a record whose design is not known, fitted from its wheelset roll and
    yaw gyroscopes and axle-box accelerometer (the whole record, offline; docs/accuracy.md,
    "Curves"): ``design_curvature``, ``design_cant`` and ``distance`` per sample, at the
    estimator's distance, to give :func:`estimate`; ``rows`` (distance, curvature, cant: a line
    file's rows) and ``transitions`` (dicts ``start``, ``end``, ``curvature``, ``cant``).
    ``half_gauge`` and ``gravity`` default to those of the design-response model
    ``design_response_file`` names (the shipped one when None; a file path). The record
    must start on a straight and be at least 200 m long; curves with less than about 6 mm of cant
    are not found."""
