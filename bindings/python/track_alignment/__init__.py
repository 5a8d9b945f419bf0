"""Lateral track alignment from inertial sensors, from Python.

The functions are the toolkit's Rust code (the estimator FMU's, the studies' metrics and the
co-simulation master), called over numpy arrays without copying them:

- :func:`estimate`: the alignment estimator, bit-equal to the AlignmentEstimator FMU (its
  ``state``, an :class:`EstimatorState`, continues a run in a later call);
- :func:`parameters`: the estimator's parameters, their types and defaults;
- :func:`band_metrics` and :func:`bandpass`: the EN 13848 band metrics of the studies, and
  :data:`BANDS`, their wavelength edges;
- :func:`simulate`: one FMU (the RailVehicle FMU) run by the master, returned as arrays;
- :func:`fit`: ``alignment-studies fit``, the estimator fitted to a vehicle FMU or to
  recordings against a reference, into a new directory;
- :func:`fit_design`: the design line (curves, transitions, cant) of a record whose design is
  not known, fitted from its wheelset gyroscopes and accelerometer, to give :func:`estimate`.

Bad input raises ``ValueError`` with the library's message; a failed run ``RuntimeError``.
The fleet pipeline on Dask is :mod:`track_alignment.fleet`.
"""

from ._native import (
    BANDS,
    EstimatorState,
    __version__,
    band_metrics,
    bandpass,
    estimate,
    fit,
    fit_design,
    parameters,
    simulate,
)

__all__ = [
    "BANDS", "EstimatorState", "__version__", "band_metrics", "bandpass", "estimate", "fit", "fit_design", "parameters",
    "simulate",
]
