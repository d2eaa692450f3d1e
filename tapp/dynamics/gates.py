"""Manoeuvre execution errors after Gates (1963): four components, their partials and moments.

A commanded velocity change Δv (km/s, any axes) is executed as Δv + ε with, after Gates,

.. math::

    \\varepsilon = (\\sigma_1 n_1 \\lvert\\Delta v\\rvert + \\sigma_2 n_2)\\,\\hat u
        + (\\sigma_3 \\lvert\\Delta v\\rvert)\\,(n_3 \\hat e_1 + n_4 \\hat e_2)
        + \\sigma_4\\,(n_5 \\hat e_1 + n_6 \\hat e_2), \\qquad
    \\hat u = \\Delta v / \\lvert\\Delta v\\rvert,

n_i independent unit normals and (û, ê₁, ê₂) a right-handed orthonormal triad
(:func:`pointing_axes`):

1. magnitude error proportional to |Δv| (σ₁, a fraction), along Δv;
2. fixed magnitude error (σ₂, km/s), along Δv (shut-off impulse, accelerometer resolution);
3. pointing error proportional to |Δv| (σ₃, rad, small angles), on each of the two axes
   perpendicular to Δv;
4. fixed pointing error (σ₄, km/s per perpendicular axis), independent of |Δv|.

Written as a linear model in the six parameters q = (q₁ … q₆) =
(magnitude proportional, magnitude fixed, pointing proportional ê₁ and ê₂, pointing fixed ê₁
and ê₂), units (1, km/s, rad, rad, km/s, km/s),

.. math::

    \\varepsilon = G(\\Delta v)\\,q, \\qquad
    G = [\\,\\Delta v,\\ \\hat u,\\ \\lvert\\Delta v\\rvert \\hat e_1,
        \\ \\lvert\\Delta v\\rvert \\hat e_2,\\ \\hat e_1,\\ \\hat e_2\\,],
    \\qquad q \\sim N(0, \\operatorname{diag}(\\sigma_1^2, \\sigma_2^2, \\sigma_3^2,
        \\sigma_3^2, \\sigma_4^2, \\sigma_4^2)),

so that E[εεᵀ | Δv] = G diag(σ²) Gᵀ = (σ₁²|Δv|² + σ₂²) ûûᵀ + (σ₃²|Δv|² + σ₄²)(I − ûûᵀ).
TAPP I flies the six as parameters of each manoeuvre (:mod:`tapp.dynamics.manoeuvres`), TAPP II
samples them (:mod:`tapp.guidance.execution`) with this code; its Monte Carlo draws the same law
in a reduced form (:mod:`tapp.guidance.montecarlo`), tested against :class:`GatesErrors`.

Over zero-mean corrections of covariance P = E[ΔvΔvᵀ] the second moment is, when the two fixed
σ's are equal (σ₂ = σ₄: the fixed error is then isotropic, σ₂² I),

.. math::

    E[\\varepsilon\\varepsilon^T] = \\sigma_1^2 P + \\sigma_3^2 (\\operatorname{tr}P\\,I - P)
        + \\sigma_2^2 I,

exactly, whatever the distribution of Δv. With σ₂ ≠ σ₄ it needs E[ûûᵀ], which depends on the
distribution of Δv and not on P alone: :meth:`GatesErrors.second_moment` refuses it.

References
----------
C. R. Gates, "A simplified model of midcourse maneuver execution errors", JPL Technical
Report 32-504 (1963).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: The four error sources, in the order of :class:`GatesErrors`'s fields.
SOURCES = ("magnitude_proportional", "magnitude_fixed", "pointing_proportional",
           "pointing_fixed")
#: The six parameters q (columns of G), with their units and their source.
PARAMETERS = (("mag_prop", "1", 0), ("mag_fixed_km_s", "km/s", 1),
              ("point_prop_1_rad", "rad", 2), ("point_prop_2_rad", "rad", 2),
              ("point_fixed_1_km_s", "km/s", 3), ("point_fixed_2_km_s", "km/s", 3))
#: Columns of G that scale with |Δv| (the proportional sources), and the fixed ones.
PROPORTIONAL = np.array([True, False, True, True, False, False])
#: Largest proportional magnitude σ₁ (exclusive): a fraction of |Δv| below 1.
MAX_PROPORTIONAL = 1.0
#: Largest pointing σ₃, rad: the model adds pointing errors as small angles.
MAX_POINTING_rad = 0.2
#: Largest fixed σ₂, σ₄, km/s: 1 km/s, more than the whole budget of a spacecraft's propulsion
#: (shut-off transients and attitude coupling are mm/s to cm/s). Without a bound, 1e150 mm/s
#: failed in TAPP II's linear algebra and 1e300 overflowed its square.
MAX_FIXED_km_s = 1.0
#: Standard normals a sample draws per manoeuvre (:meth:`GatesErrors.sample`): n (1), g (3),
#: f (3).
NORMALS_PER_SAMPLE = 7


class GatesRangeError(ValueError):
    """A σ outside its range: ``field`` names it, ``expected`` says the range."""

    def __init__(self, field: str, expected: str, got: float):
        self.field, self.expected, self.got = field, expected, got
        super().__init__(f"{field}: expected {expected} (got {got!r})")


def _check(name: str, value: float, hi: float, inclusive: bool, unit: str) -> None:
    ok = math.isfinite(value) and 0 <= value and (value <= hi if inclusive else value < hi)
    if not ok:
        bound = f"<= {hi:g}" if inclusive else f"< {hi:g}"
        raise GatesRangeError(name, f"a finite number >= 0 and {bound}{unit}", value)


@dataclass(frozen=True, slots=True)
class GatesErrors:
    """1σ of Gates' four execution-error sources (module docstring).

    Attributes
    ----------
    sigma_magnitude_proportional : σ₁, fraction of |Δv|, in [0, :data:`MAX_PROPORTIONAL`).
    sigma_magnitude_fixed_km_s : σ₂, km/s, in [0, :data:`MAX_FIXED_km_s`].
    sigma_pointing_proportional_rad : σ₃, rad per perpendicular axis, in
        [0, :data:`MAX_POINTING_rad`].
    sigma_pointing_fixed_km_s : σ₄, km/s per perpendicular axis, in [0, :data:`MAX_FIXED_km_s`].

    Raises
    ------
    GatesRangeError
        A σ outside its range, NaN or infinite (naming the field).
    """

    sigma_magnitude_proportional: float = 0.0
    sigma_magnitude_fixed_km_s: float = 0.0
    sigma_pointing_proportional_rad: float = 0.0
    sigma_pointing_fixed_km_s: float = 0.0

    def __post_init__(self) -> None:
        _check("sigma_magnitude_proportional", self.sigma_magnitude_proportional,
               MAX_PROPORTIONAL, False, "")
        _check("sigma_magnitude_fixed_km_s", self.sigma_magnitude_fixed_km_s, MAX_FIXED_km_s,
               True, " km/s")
        _check("sigma_pointing_proportional_rad", self.sigma_pointing_proportional_rad,
               MAX_POINTING_rad, True, " rad")
        _check("sigma_pointing_fixed_km_s", self.sigma_pointing_fixed_km_s, MAX_FIXED_km_s,
               True, " km/s")

    @property
    def sources(self) -> np.ndarray:
        """(σ₁, σ₂, σ₃, σ₄), (4,), in the units of the fields."""
        return np.array([self.sigma_magnitude_proportional, self.sigma_magnitude_fixed_km_s,
                         self.sigma_pointing_proportional_rad, self.sigma_pointing_fixed_km_s])

    @property
    def sigmas(self) -> np.ndarray:
        """σ of the six parameters q (:data:`PARAMETERS`), (6,)."""
        return self.sources[[source for _, _, source in PARAMETERS]]

    def covariance(self, dv_km_s: np.ndarray) -> np.ndarray:
        """E[εεᵀ | Δv] = G diag(σ²) Gᵀ, (..., 3, 3) km²/s², for Δv (..., 3) km/s."""
        g = gates_partials(dv_km_s) * self.sigmas
        return g @ np.swapaxes(g, -1, -2)

    def second_moment(self, P: np.ndarray) -> np.ndarray:
        """E[εεᵀ] (3, 3), km²/s², over zero-mean corrections of covariance ``P`` (km²/s²).

        .. math:: E[\\varepsilon\\varepsilon^T] = \\sigma_1^2 P
            + \\sigma_3^2 (\\operatorname{tr}P\\,I - P) + \\sigma_2^2 I

        >>> GatesErrors(0.5, 0.0, 0.1, 0.0).second_moment(np.diag([4.0, 1.0, 0.0]))
        array([[1.01, 0.  , 0.  ],
               [0.  , 0.29, 0.  ],
               [0.  , 0.  , 0.05]])

        Raises
        ------
        ValueError
            With σ₂ ≠ σ₄ (the moment then depends on more than P: module docstring).
        """
        s1, s2, s3, s4 = self.sources
        if s2 != s4:
            raise ValueError("the second moment over a covariance of corrections needs equal "
                             f"fixed magnitude and pointing σ (got {s2!r} and {s4!r} km/s)")
        eye = np.eye(3)
        return s1**2 * P + s3**2 * (np.trace(P) * eye - P) + s2**2 * eye

    def sample(self, dv_km_s: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """Return execution errors ε (n, 3), km/s, of commanded corrections Δv (n, 3), km/s.

        ``normals`` (n, :data:`NORMALS_PER_SAMPLE`) are independent unit normals (n, g, f): q
        = σ ⊙ (n, û·f, ê₁·g, ê₂·g, ê₁·f, ê₂·f), the projections of the isotropic g and f on
        the triad, so that the proportional pointing error is σ₃ |Δv| (I − ûûᵀ) g and, with
        σ₂ = σ₄, the fixed error is σ₂ f (to rounding) whatever the triad. Since
        ê₁ê₁ᵀ + ê₂ê₂ᵀ = I − ûûᵀ, ε = G q needs no triad:

        .. math:: \\varepsilon = \\left(\\sigma_1 n |\\Delta v| + (\\sigma_2 - \\sigma_4)
            (\\hat u\\cdot f) - \\sigma_3 |\\Delta v| (\\hat u\\cdot g)\\right)\\hat u
            + \\sigma_3 |\\Delta v|\\, g + \\sigma_4 f

        (û = x̂ for Δv = 0, as :func:`pointing_axes`); G q itself agrees to rounding (tests).
        Row i of the result depends on row i of the inputs only.
        """
        dv = np.asarray(dv_km_s, dtype=float)
        size = np.sqrt(_dot(dv, dv))
        u = np.where(size[:, None] > 0, dv / np.where(size > 0, size, 1.0)[:, None],
                     np.array([1.0, 0.0, 0.0]))
        s1, s2, s3, _, s4, _ = self.sigmas
        n, g, f = normals[:, 0], normals[:, 1:4], normals[:, 4:7]
        along = s1 * n * size + (s2 - s4) * _dot(u, f) - s3 * size * _dot(u, g)
        return along[:, None] * u + (s3 * size)[:, None] * g + s4 * f


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot products of (n, 3) arrays, (n,)."""
    return np.einsum("si,si->s", a, b)


def pointing_axes(dv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the triad (û, ê₁, ê₂), each (..., 3), of velocity changes ``dv`` (..., 3).

    û = Δv/|Δv| (the first axis, x̂, for Δv = 0); ê₁ is the coordinate axis â least aligned
    with û (the first such, on ties) made perpendicular to it, ê₁ = (â − (â·û)û)/|…|; ê₂ =
    û × ê₁. For û along a coordinate axis, ê₁ and ê₂ are the next two, exactly (x̂ → ŷ, ẑ).
    """
    dv = np.asarray(dv, dtype=float)
    norm = np.linalg.norm(dv, axis=-1, keepdims=True)
    first = np.zeros_like(dv)
    first[..., 0] = 1.0
    u = np.where(norm > 0, dv / np.where(norm > 0, norm, 1.0), first)
    a = np.eye(3)[np.argmin(np.abs(u), axis=-1)]
    e1 = a - np.sum(a * u, axis=-1, keepdims=True) * u
    e1 = e1 / np.linalg.norm(e1, axis=-1, keepdims=True)
    return u, e1, np.cross(u, e1)


def gates_partials(dv_km_s: np.ndarray) -> np.ndarray:
    """Return G = ∂ε/∂q = [Δv, û, |Δv| ê₁, |Δv| ê₂, ê₁, ê₂], (..., 3, 6), for Δv (..., 3) km/s
    (module docstring; columns in the units of :data:`PARAMETERS`: km/s per unit of q)."""
    dv = np.asarray(dv_km_s, dtype=float)
    u, e1, e2 = pointing_axes(dv)
    mag = np.linalg.norm(dv, axis=-1, keepdims=True)
    return np.stack([dv, u, mag * e1, mag * e2, e1, e2], axis=-1)


__all__ = ["MAX_FIXED_km_s", "MAX_POINTING_rad", "MAX_PROPORTIONAL", "NORMALS_PER_SAMPLE",
           "PARAMETERS", "PROPORTIONAL", "SOURCES", "GatesErrors", "GatesRangeError",
           "gates_partials", "pointing_axes"]
