"""The ``[noise]`` table of tracking scenarios and of the study file: measurement noise.

Keys are ``<part>_<kind>_<unit>``, the kinds and edge units of
:data:`tapp.measurements.noise.EDGE_UNITS` (range in m, range rate and count-based Doppler in
mm/s, angles in deg; Doppler also ``<part>_doppler_hz``, converted at the station's band by
:func:`tapp.measurements.doppler.range_rate_from_hz`, one of the two)::

    [noise.fit]                  # the fit world: white noise, weights W = diag(1/σ²)
    sigma_range_m = 1.0
    sigma_range_rate_mm_s = 0.1
    [noise.real]                 # the real world (tracking scenarios only)
    sigma_range_m = 1.5          # white σ (default: the fit σ)
    bias_range_m = 2.0           # a constant per pass, σ
    correlated_range_rate_mm_s = 0.05   # exponentially correlated, σ ...
    tau_range_rate_s = 600.0     # ... and its time constant

A tracking scenario's stations may override any key in ``[tracking.station.NAME.fit]`` and
``[tracking.station.NAME.real]``. The study file's data are white noise of its
``[noise.fit]`` σ, which its fits also assume.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from tapp.io.schema import Schema

Positive = Annotated[float, Field(gt=0)]
NonNegative = Annotated[float, Field(ge=0)]


class FitTable(Schema):
    """``[noise.fit]``: the white-noise σ of each observable kind that the fit assumes."""

    sigma_range_m: Positive | None = Field(None, description="σ of range observations.")
    sigma_range_rate_mm_s: Positive | None = Field(
        None, description="σ of range-rate observations.")
    sigma_azimuth_deg: Positive | None = Field(None, description="σ of azimuth observations.")
    sigma_elevation_deg: Positive | None = Field(
        None, description="σ of elevation observations.")
    sigma_doppler_mm_s: Positive | None = Field(
        None, description="σ of count-based Doppler (equivalent range-rate), or:")
    sigma_doppler_hz: Positive | None = Field(
        None, description="the same σ in Hz at the station's band (2 M₂ f_T / c per km/s).")


_WHITE = "White-noise σ of {} observations in the real world; default: the fit world's."
_BIAS = "σ of a constant {} bias drawn anew for each pass (0: none)."
_CORRELATED = "σ of exponentially correlated {} noise (first-order Gauss-Markov; 0: none)."
_TAU = "Time constant of the correlated {} noise (needed when its σ is > 0)."


class RealTable(Schema):
    """``[noise.real]``: the noise the data truly have: white σ, per-pass bias σ, correlated
    σ with its time constant, for each observable kind."""

    sigma_range_m: NonNegative | None = Field(None, description=_WHITE.format("range"))
    sigma_range_rate_mm_s: NonNegative | None = Field(
        None, description=_WHITE.format("range-rate"))
    sigma_azimuth_deg: NonNegative | None = Field(None, description=_WHITE.format("azimuth"))
    sigma_elevation_deg: NonNegative | None = Field(
        None, description=_WHITE.format("elevation"))
    bias_range_m: NonNegative | None = Field(None, description=_BIAS.format("range"))
    bias_range_rate_mm_s: NonNegative | None = Field(
        None, description=_BIAS.format("range-rate"))
    bias_azimuth_deg: NonNegative | None = Field(None, description=_BIAS.format("azimuth"))
    bias_elevation_deg: NonNegative | None = Field(None, description=_BIAS.format("elevation"))
    correlated_range_m: NonNegative | None = Field(None, description=_CORRELATED.format("range"))
    correlated_range_rate_mm_s: NonNegative | None = Field(
        None, description=_CORRELATED.format("range-rate"))
    correlated_azimuth_deg: NonNegative | None = Field(
        None, description=_CORRELATED.format("azimuth"))
    correlated_elevation_deg: NonNegative | None = Field(
        None, description=_CORRELATED.format("elevation"))
    tau_range_s: Positive | None = Field(None, description=_TAU.format("range"))
    tau_range_rate_s: Positive | None = Field(None, description=_TAU.format("range-rate"))
    tau_azimuth_s: Positive | None = Field(None, description=_TAU.format("azimuth"))
    tau_elevation_s: Positive | None = Field(None, description=_TAU.format("elevation"))
    sigma_doppler_mm_s: NonNegative | None = Field(None, description=_WHITE.format("Doppler"))
    sigma_doppler_hz: NonNegative | None = Field(None, description=_WHITE.format("Doppler")
                                                 + " In Hz at the station's band.")
    bias_doppler_mm_s: NonNegative | None = Field(None, description=_BIAS.format("Doppler"))
    bias_doppler_hz: NonNegative | None = Field(None, description=_BIAS.format("Doppler")
                                                + " In Hz at the station's band.")
    correlated_doppler_mm_s: NonNegative | None = Field(
        None, description=_CORRELATED.format("Doppler"))
    correlated_doppler_hz: NonNegative | None = Field(
        None, description=_CORRELATED.format("Doppler") + " In Hz at the station's band.")
    tau_doppler_s: Positive | None = Field(None, description=_TAU.format("Doppler"))


class NoiseTable(Schema):
    """``[noise]``: the fit world (required) and the real world."""

    fit: FitTable = Field(description="The noise the fit assumes (white).")
    real: RealTable = Field(RealTable(), description="The noise the data have; default: the "
                            "fit world's white noise.")
