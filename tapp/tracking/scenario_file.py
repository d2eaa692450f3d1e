"""The tracking scenario file (TOML) of TAPP I: its tables and keys, declared as one schema.

A scenario gives the trajectory (epoch, injection state, state and variational force models),
the parameter vector x = [p; q], the tracking stations and schedule, the fit-world and
real-world noise, the T13 times (input times and epoch times) and the miss parameters.
The examples ``leo_equatorial.toml`` and ``deep_space.toml`` (``tapp examples``) are commented.
The file is validated against one declared schema, :class:`ScenarioFile` (``tapp.io.schema``):
unknown tables and keys are errors naming the allowed keys, booleans are not numbers, numbers
are not strings; the rules between tables and the physics are checked while it is built
(:mod:`tapp.tracking.scenario_build`) into a :class:`tapp.tracking.scenario.Scenario`.

Tables and keys (units in the key names; times are seconds from the epoch, or UTC dates as
ISO strings or TOML dates)::

    title = "..."                   iden = "..."  (tape identification, default: file stem)
    epoch = "2026-01-01T00:00:00"   UTC of the injection, t = 0 (scenario time t is SI seconds
                                    from it: a date across a leap second counts it)
    earth_orientation = "iau2006"   or "gmst" (tapp.frames.orientation; stations, the field)
    eop = "iers"                    Earth orientation parameters: "iers" (the shipped IERS
                                    table), "none" (UT1 = UTC, no polar motion: a study
                                    beyond the predictions) or a finals2000A file path
    [injection]        r_km = [3], v_km_s = [3]   (EME2000, Earth-centred), or classical
                       elements a_km, e, i_deg, raan_deg, argp_deg and M_deg or nu_deg;
                       allow_subsurface = true accepts an orbit whose perigee is below the
                       Earth's surface (refused otherwise, ``tapp.io.orbits.check_perigee``)
    [reference]        instead of [injection]: the mission's trajectory, file = an SPK or
                       OEM (relative to this file), object, max_fit_error_m, fit_manoeuvres,
                       step_s; TAPP I flies its force model fitted to it over each arc
                       between the burns (tapp.tracking.reference)
    [model]            gravity (J0 | Jn | NxM), third_bodies (each once), var_gravity,
                       var_third_bodies (the variational model: the seed's truncated
                       variational equations; default the state model), rtol, atol (within
                       ``tapp.dynamics.propagate.TOLERANCE_RANGE``, 1e-15 to 1e-6), method
                       ("dop853" default, or "rkn12": ``tapp.dynamics.propagate``);
                       surface forces of a cannonball (tapp.io.models_file):
                       area_to_mass_m2_kg, c_r, c_d, srp / var_srp, shadows /
                       var_shadows, atmosphere / var_atmosphere ("none", "exponential",
                       "harris_priester")
    [parameters]       dynamic = ["GM_km3_s2", "GM_moon_km3_s2", "J2", "C22", "Cr", "Cd",
                       "dr_mars_x_km", ...] (named as on the tape: tapp.dynamics.parameters;
                       GM, GM_moon, dr_mars_x are read with a warning; dr_<body>_x_km: a
                       third body's ephemeris offset, km, not the Earth's:
                       tapp.dynamics.ephemeris_offsets),
                       station_location = "cylindrical" |
                       "ecef" | "none", station_biases = ["range", "range_rate",
                       "doppler"],
                       media = ["troposphere", "ionosphere"] (each station's zenith
                       parameters <STATION>.zenith_dry_km, .zenith_wet_km, kind
                       "troposphere", and .zenith_tec_tecu, kind "ionosphere"; needs
                       the effect on in [media]), media_per = "station" | "pass" (one
                       set per station, or one per pass: <STATION>.zenith_wet_km.p1, ...,
                       numbered in the station's pass order once the passes are known),
                       earth_orientation = true | ["ut1_s", "xp_rad", "yp_rad"] (constant
                       EOP offsets eop.*, kind "eop"; gmst: ut1_s only),
                       earth_orientation_per = "arc" | "day" (one offset over the arc, or
                       one per UTC day of the tracking window, eop.<name>.<YYYY-MM-DD>:
                       tapp.tracking.eop_days),
                       [parameters.values] non-nominal values of dynamic parameters
    [stations.NAME]    lat_deg, lon_deg, h_km (-0.5 to 10 km), elev_mask_deg
                       (tapp.io.stations_file)
    [tracking]         stations = [names], observables = ["range", "range_rate", "azimuth",
                       "elevation", "doppler"], light_time = "none" | "one_way" | "two_way",
                       band = "S" | "X" | "Ka" (tapp.measurements.bands), data_interval_s,
                       start, end, min_pass_s, max_pass_s,
                       blackouts = [[start, end], ...], schedule (a pass schedule, CSV:
                       tapp.io.schedule_file), use = "visibility" | "schedule" | "both",
                       allow_partial (tapp.tracking.schedule), relativity = "auto" | true |
                       false (tapp.measurements.relativity), count_time_s (doppler)
    [tracking.station.NAME]  per-station observables, location, biases, range_bias_m,
                       range_rate_bias_mm_s (nominal bias values), blackouts, uplink (the
                       station transmitting its three-way up-leg), and fit / real
                       tables overriding [noise.fit] / [noise.real] keys; the media's
                       pressure_hpa, temperature_k, relative_humidity (default: the
                       standard atmosphere at its height) and zenith_tec_tecu
    [media]            optional: troposphere = true, ionosphere = true (both default false)
                       add their delays to every station's range, range-rate and Doppler
                       (a three-way up-leg through its uplink station's; not to ΔDOR);
                       shell_height_km (350), zenith_tec_tecu (10) (tapp.measurements.media)
    [noise.fit]        sigma_range_m, sigma_range_rate_mm_s, sigma_azimuth_deg,
                       sigma_elevation_deg, sigma_doppler_mm_s or sigma_doppler_hz (white
                       noise: W = diag(1/σ²))
    [noise.real]       sigma_<kind>_<unit> (white, default the fit σ), bias_<kind>_<unit>
                       (constant per pass), correlated_<kind>_<unit> with tau_<kind>_s
                       (exponentially correlated)
    [ddor]             optional: ΔDOR on baselines of tracked stations (baselines, interval_s,
                       min_window_s, quasar_separation_deg, quasar_position_angle_deg,
                       quasar_position = true: A-B.quasar_ra_rad, .quasar_dec_rad in q;
                       [ddor.fit] sigma_ns or sigma_nrad, [ddor.real] sigma_*, bias_*;
                       tapp.tracking.ddor)
    [times]            input = [times] or input_step_s with end; epochs = [times] (epoch times
                       after t_0 = 0; re-epoching as in seed TAPP III §4.1)
    [miss]             kind = "bplane" (body, reference; b_dot_r_km, b_dot_t_km, ltof_s,
                       flight_time_s, entry_fpa_rad) | "equinoctial" (a_km, ex, ey, hx, hy,
                       lambda_m_rad) | "classical" (a_km, e, i_rad, raan_rad, argp_rad,
                       M_rad); time (a B-plane's may be "periapsis": the trajectory's first
                       periapsis at the body, found as SEARCH finds it); quantities (default:
                       all of the kind but flight_time_s and entry_fpa_rad). reference =
                       "earth_equator" (default, EME2000 xy) | "ecliptic" | "body_equator"
                       (the body's own equator, its IAU pole at the miss time; the Earth's
                       is EME2000 xy; bodies: tapp.dynamics.poles.EQUATOR_POLE_BODIES).
                       entry_fpa_rad: the flight-path angle (< 0) where the osculating
                       hyperbola at the miss time crosses entry_radius_km (required with
                       it, refused without; tapp.orbit.bplane.entry_flight_path_angle). A
                       B-plane miss must be an encounter (tapp.tracking.encounter), checked
                       before anything is written.
    [stochastic]       optional: piecewise-constant stochastic accelerations
                       (tapp.estimation.gauss_markov): frame = "ric" | "inertial",
                       components (default all three), interval_s with start, end (default
                       0 and the last T13 time; the last interval may be shorter) or
                       boundaries = [times], sigma_km_s2 or sigma_m_s2, tau_s (first-order
                       Gauss-Markov across the intervals); one parameter acc_<c>_<k> (km/s²,
                       kind "stochastic") per interval and component, appended to x
    [[manoeuvre]]      optional, one table per burn (tapp.tracking.manoeuvres): kind =
                       "impulsive" (time, dv_m_s or dv_km_s) or "finite" (start, duration_s,
                       thrust_N, direction, mass_kg, mass_flow_kg_s), axes = "inertial" |
                       "ric" | "vnb", Gates' four σ; one parameter <name>.<component> (kind
                       "execution") per error source with σ > 0, appended to x
    [targeting]        optional: retarget the injection velocity to a B-plane aim point of the
                       miss body by SEARCH before simulating
                       (tapp.targeting.searchfile.scenario_targeting: targets.b_dot_r_km,
                       targets.b_dot_t_km, targets.flight_time_s, vary, first_guess,
                       tolerances, increments, SEARCH's iteration control and scan); needs
                       miss.time = "periapsis" and nominal parameter values
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from tapp.estimation.gauss_markov import FRAMES
from tapp.frames.orientation import EOP_PARAMETERS
from tapp.io.models_file import ModelTable
from tapp.io.noise_file import FitTable, NoiseTable, NonNegative, Positive, RealTable
from tapp.io.orbits import OrbitTable
from tapp.io.schema import EarthOrientationName, EopSource, Schema, Time, Unique, UtcDate
from tapp.io.stations_file import StationsSection
from tapp.io.trajectory_file import ReferenceTable
from tapp.measurements.bands import BAND_NAMES, DEFAULT_BAND
from tapp.measurements.media import ZENITH_TEC_TECU, SHELL_HEIGHT_km
from tapp.orbit.bplane import REFERENCE_PLANES
from tapp.targeting.program import REFERENCE_HELP
from tapp.targeting.searchfile import TargetingTable
from tapp.tracking.ddor import DdorTable
from tapp.tracking.manoeuvres import MAX_MANOEUVRES, ManoeuvreTable
from tapp.tracking.scenario import (
    BIAS_KINDS,
    KINDS,
    LIGHT_TIME_MODES,
    LOCATION_MODES,
    MEDIA_EFFECTS,
    MISS_QUANTITIES,
    USES,
)

#: Most T13 input times a scenario may ask for (each is a tape record, held in memory).
MAX_INPUT_TIMES = 100_000


Window = Annotated[list[Time], Field(min_length=2, max_length=2)]
Kind = Literal[KINDS]  # type: ignore[valid-type]
BiasKind = Literal[BIAS_KINDS]  # type: ignore[valid-type]
LocationMode = Literal[LOCATION_MODES]  # type: ignore[valid-type]
BandName = Literal[BAND_NAMES]  # type: ignore[valid-type]

_LOCATION = ("How station locations enter q: \"cylindrical\" (distance from the spin axis, "
             "longitude, height along the axis), \"ecef\" (x, y, z) or \"none\".")
_BIASES = "Observable kinds whose per-station bias is a parameter in q."
_BLACKOUTS = "Windows [start, end] without data"


class ParametersTable(Schema):
    """``[parameters]``: the parameters q of x = [p; q] beside the epoch state p."""

    dynamic: Annotated[list[str], Unique] = Field(
        [], description="Model parameters in q, named as on the tape: \"GM_km3_s2\" (the "
        "centre's), \"GM_moon_km3_s2\" (a third body's), \"J2\", \"C22\", \"S22\", ... of "
        "the state model, \"Cr\" (with model.srp), \"Cd\" (with a model.atmosphere) and "
        "\"dr_mars_x_km\", \"dr_mars_y_km\", \"dr_mars_z_km\" (a third body's ephemeris "
        "offset, km, ICRF; not the Earth's). The earlier spellings GM, GM_moon, dr_mars_x are "
        "read with a warning.")
    station_location: LocationMode = Field("none", description=_LOCATION)
    station_biases: Annotated[list[BiasKind], Unique] = Field([], description=_BIASES)
    media: Annotated[list[Literal[MEDIA_EFFECTS]], Unique] = Field(  # type: ignore[valid-type]
        [], description="Media whose per-station zenith parameters are in q: "
        "\"troposphere\" (zenith_dry_km, zenith_wet_km), \"ionosphere\" (zenith_tec_tecu); "
        "each needs its effect on in [media].")
    media_per: Literal["station", "pass"] = Field(
        "station", description="The zenith parameters' span: one set per station over the arc "
        "(STATION.zenith_wet_km), or one per pass, its calibration's (STATION.zenith_wet_km.p1, "
        ".p2, ... in the station's pass order, named once TAPP I has found the passes).")
    values: dict[str, float] = Field(
        {}, description="Values other than nominal of dynamic parameters, by name "
        "(GM_km3_s2 in km³/s²).")
    earth_orientation: bool | Annotated[list[Literal[EOP_PARAMETERS]],  # type: ignore[valid-type]
                                        Unique] = Field(
        False, description="Constant offsets of the Earth orientation parameters from the IERS "
        "values in q (eop.ut1_s, eop.xp_rad, eop.yp_rad): true for all (\"ut1_s\" alone under "
        "gmst), or a list of them.")
    earth_orientation_per: Literal["arc", "day"] = Field(
        "arc", description="The offsets' span: one over the whole arc (eop.<name>), or one per "
        "UTC day of the tracking window (eop.<name>.<YYYY-MM-DD>, each moving only its day's "
        "observations).")


class StationTracking(Schema):
    """``[tracking.station.NAME]``: what one station measures and how, overriding the
    scenario's defaults."""

    observables: Annotated[list[Kind], Field(min_length=1), Unique] | None = Field(
        None, description="What the station measures; default: tracking.observables.")
    location: LocationMode | None = Field(
        None, description="Its location parameters; default: parameters.station_location.")
    biases: Annotated[list[BiasKind], Unique] | None = Field(
        None, description="Its bias parameters; default: parameters.station_biases.")
    range_bias_m: float = Field(0.0, description="Nominal range bias added to its range.")
    range_rate_bias_mm_s: float = Field(0.0, description="Nominal range-rate bias added to "
                                        "its range rate.")
    blackouts: list[Window] = Field([], description=_BLACKOUTS + " at this station (beside "
                                    "tracking.blackouts).")
    band: BandName | None = Field(None, description="Its radio band; default: tracking.band.")
    doppler_bias_mm_s: float = Field(0.0, description="Nominal bias added to its count-based "
                                     "Doppler.")
    fit: FitTable = Field(FitTable(), description="Its fit-world σ, overriding [noise.fit].")
    real: RealTable = Field(RealTable(), description="Its real-world noise, overriding "
                            "[noise.real].")
    pressure_hpa: Positive | None = Field(
        None, description="Surface pressure for the zenith hydrostatic delay (300 to 1100 "
        "hPa); default: the standard atmosphere at its height.")
    temperature_k: Positive | None = Field(
        None, description="Surface temperature for the zenith wet delay (180 to 340 K); "
        "default: the standard atmosphere at its height.")
    relative_humidity: NonNegative | None = Field(
        None, description="Relative humidity, a fraction 0 to 1; default: 0.5.")
    zenith_tec_tecu: NonNegative | None = Field(
        None, description="Its nominal zenith TEC (TECU); default: media.zenith_tec_tecu.")
    uplink: str | None = Field(
        None, description="Three-way tracking: the [stations.NAME] station that transmits the "
        "up-leg this station receives (light_time = \"two_way\"; the up-leg's location "
        "partials go to its columns when it is tracked with location parameters); default: "
        "itself (two-way).")


class TrackingTable(Schema):
    """``[tracking]``: the stations, what they measure and when. Samples fall every
    ``data_interval_s`` from ``start`` to ``end`` while a station sees the spacecraft above
    its mask and outside blackouts; a pass is a run of such samples. A ``schedule`` gives the
    passes instead (``use``)."""

    stations: Annotated[list[str], Field(min_length=1), Unique] = Field(
        description="Names of [stations.NAME] tables, numbered 1, 2, ... on the tape.")
    observables: Annotated[list[Kind], Unique] = Field(
        ["range", "range_rate"], description="What every station measures.")
    light_time: Literal[LIGHT_TIME_MODES] = Field(  # type: ignore[valid-type]
        "none", description="Light-time correction of the observables.")
    band: BandName = Field(DEFAULT_BAND, description="The stations' radio band, \"S\", \"X\" "
                           "or \"Ka\": the carrier frequencies of their links (uplink, and "
                           "downlink by the DSN's turnaround ratio).")
    data_interval_s: Positive = Field(description="Time between samples of each station.")
    start: Time = Field(0.0, description="First sample time.")
    end: Time | None = Field(None, description="Last sample time; default: the last T13 time.")
    min_pass_s: NonNegative = Field(0.0, description="Passes shorter than this are dropped.")
    max_pass_s: Positive | None = Field(
        None, description="Passes longer than this are split (each piece its own per-pass "
        "bias); default: no limit.")
    blackouts: list[Window] = Field([], description=_BLACKOUTS + " at every station.")
    station: dict[str, StationTracking] = Field(
        {}, description="Per-station overrides, by station name.")
    schedule: str | None = Field(
        None, description="A pass schedule (CSV, relative to the scenario's folder): a header, "
        "then one row per pass: station, start, end (UTC dates or seconds from the epoch), "
        "data_types (observables separated by spaces; empty: the station's), data_interval_s "
        "(empty: tracking.data_interval_s), uplink_station (empty, the station itself, or its "
        "tracking.station.NAME.uplink for three-way); tapp.io.schedule_file.")
    use: Literal[USES] | None = Field(  # type: ignore[valid-type]
        None, description="Which samples: \"visibility\" (the grid, wherever a station sees "
        "the spacecraft), \"schedule\" (the schedule's passes only) or \"both\" (the stations "
        "with passes in the schedule in them, the others by visibility); default: "
        "\"schedule\" with a schedule, else \"visibility\".")
    allow_partial: bool = Field(
        False, description="Drop the samples of a scheduled pass that the station cannot see "
        "(counted under elevation_mask) instead of refusing the schedule.")
    relativity: Literal["auto"] | bool = Field(
        "auto", description="Relativistic light time (barycentric, TDB, Shapiro delays: "
        "tapp.measurements.relativity): true, false, or \"auto\": on with light_time = "
        "\"two_way\" when the spacecraft goes beyond the Moon's distance (384,400 km) in "
        "the tracking span.")
    count_time_s: Positive | None = Field(
        None, description="Count interval of the doppler observable (centred on each sample), "
        "s, at most data_interval_s; default: 60 s or data_interval_s if shorter.")


class MediaTable(Schema):
    """``[media]``: the troposphere and ionosphere on every station's range and range-rate
    (tapp.measurements.media; ΔDOR is left without them)."""

    troposphere: bool = Field(False, description="Saastamoinen-Davis zenith delays from each "
                              "station's weather, mapped by Niell (1996).")
    ionosphere: bool = Field(False, description="A thin-shell ionosphere: 40.3 TEC / f² at "
                             "each leg's carrier, a delay on range and an advance on "
                             "range-rate.")
    shell_height_km: Positive = Field(SHELL_HEIGHT_km, description="Height of the thin shell.")
    zenith_tec_tecu: NonNegative = Field(
        ZENITH_TEC_TECU, description="Every station's nominal zenith TEC, TECU (1e16 /m²); "
        "10 is Klobuchar's night-time floor, a mid-latitude day 20-50.")


class TimesTable(Schema):
    """``[times]``: the T13 times: input times (tape records) and epoch times (the state the
    information is referred to is re-epoched there; t = 0 is always one)."""

    input: list[Time] | None = Field(None, description="Input times, ascending, after 0 (or "
                                     "input_step_s with end).")
    input_step_s: Positive | None = Field(None, description="Input times every this many "
                                          "seconds up to end.")
    end: Time | None = Field(None, description="The last input time, with input_step_s.")
    epochs: list[Time] = Field([], description="Epoch times after t = 0, ascending, up to the "
                               "last input time.")


class MissTable(Schema):
    """``[miss]``: the miss parameters whose partials the tape carries. A B-plane miss must be
    an encounter: the spacecraft inside the body's sphere of attraction, on a hyperbola."""

    kind: Literal[tuple(MISS_QUANTITIES)] = Field(  # type: ignore[valid-type]
        description="\"bplane\" (b_dot_r_km, b_dot_t_km, ltof_s, flight_time_s, entry_fpa_rad), "
        "\"equinoctial\" (a_km, ex, ey, hx, hy, lambda_m_rad) or \"classical\" (a_km, e, "
        "i_rad, raan_rad, argp_rad, M_rad).")
    time: Time | None = Field(
        None, description="When the miss is evaluated; a B-plane's may be \"periapsis\" (the "
        "trajectory's first periapsis at the body); default: the last T13 time.")
    quantities: Annotated[list[str], Field(min_length=1), Unique] | None = Field(
        None, description="Which quantities of the kind; default: all but flight_time_s and "
        "entry_fpa_rad.")
    body: str | None = Field(None, description="The B-plane's body, a third body of the state "
                             "model.")
    reference: Literal[REFERENCE_PLANES] | None = Field(  # type: ignore[valid-type]
        None, description=f"The B-plane's reference plane (T axis): {REFERENCE_HELP}; "
        "default: \"earth_equator\".")
    entry_radius_km: Positive | None = Field(
        None, description="Atmosphere interface radius from the body's centre, km, where "
        "entry_fpa_rad is the flight-path angle of the incoming osculating hyperbola; "
        "required with entry_fpa_rad in quantities, refused without; below the distance at "
        "the miss time and at or above the hyperbola's periapsis radius.")


#: Most stochastic-acceleration parameters (intervals x components): each adds a column to
#: every factor on the tape (3 n_o² doubles per pair) and to the processor's matrices.
MAX_STOCHASTIC = 300


class StochasticTable(Schema):
    """``[stochastic]``: piecewise-constant accelerations, constant over each interval,
    correlated across intervals as a first-order Gauss-Markov process of their mid-times
    (tapp.estimation.gauss_markov); each (interval, component) is a parameter in q."""

    frame: Literal[FRAMES] = Field(  # type: ignore[valid-type]
        "ric", description="\"ric\": radial, in-track, cross-track of the trajectory; "
        "\"inertial\": x, y, z.")
    components: Annotated[list[str], Field(min_length=1), Unique] | None = Field(
        None, description="Components modelled (R, I, C or x, y, z); default: all three.")
    interval_s: Positive | None = Field(
        None, description="Interval length, from start to end (the last may be shorter); or "
        "boundaries.")
    start: Time | None = Field(None, description="Start of the first interval, with "
                               "interval_s; default: 0.")
    end: Time | None = Field(None, description="End of the last interval, with interval_s; "
                             "default: the last T13 time.")
    boundaries: Annotated[list[Time], Field(min_length=2)] | None = Field(
        None, description="Interval boundaries t_0 < ... < t_K, from 0 to the last T13 time.")
    sigma_km_s2: Positive | None = Field(None, description="Steady-state σ of each component "
                                         "(or sigma_m_s2).")
    sigma_m_s2: Positive | None = Field(None, description="The same σ in m/s².")
    tau_s: Positive = Field(description="Gauss-Markov time constant τ: consecutive intervals "
                            "correlate by exp(-Δt/τ) over their mid-times' distance Δt.")


class ScenarioFile(StationsSection):
    """Schema of a TAPP I tracking scenario (module docstring for the tables)."""

    title: str = Field("", description="Free text, kept on the tape.")
    iden: str | None = Field(None, description="Tape identification; default: the file name "
                             "up to its first dot.")
    epoch: UtcDate = Field(description="UTC of the injection, t = 0; scenario time is SI "
                           "seconds from it.")
    earth_orientation: EarthOrientationName = "iau2006"
    eop: EopSource = "iers"
    injection: OrbitTable | None = Field(
        None, description="The state at the epoch (GCRS; EME2000 with gmst); or [reference].")
    reference: ReferenceTable | None = Field(
        None, description="The mission's own trajectory, fitted by TAPP I's force model; or "
        "[injection].")
    model: ModelTable = Field(description="The state and variational force models.")
    parameters: ParametersTable = Field(ParametersTable(),
                                        description="The parameters q beside the state.")
    tracking: TrackingTable = Field(description="Who tracks, what and when.")
    noise: NoiseTable = Field(description="Fit-world and real-world measurement noise.")
    times: TimesTable = Field(description="The T13 times.")
    miss: MissTable = Field(description="The miss parameters.")
    targeting: TargetingTable | None = Field(
        None, description="Retarget the injection velocity by SEARCH before simulating.")
    ddor: DdorTable | None = Field(None, description="ΔDOR on baselines of tracked stations.")
    media: MediaTable = Field(MediaTable(), description="Troposphere and ionosphere on the "
                              "stations' range and range-rate.")
    stochastic: StochasticTable | None = Field(
        None, description="Stochastic accelerations, estimated or considered by TAPP III.")
    manoeuvre: Annotated[list[ManoeuvreTable], Field(max_length=MAX_MANOEUVRES)] = Field(
        [], description="Burns, impulsive or finite, with their execution errors "
        "(tapp.tracking.manoeuvres).")
