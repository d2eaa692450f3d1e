"""The DSN's radio bands: the carrier frequencies a station transmits and receives.

A station's ``band`` sets the frequencies its links are modelled at: the uplink carrier f_T
the station transmits and the downlink f_R = M₂ f_T the spacecraft's coherent transponder
returns, with the DSN's standard turnaround ratios M₂ (JPL 810-005, Telecommunications Link
Design Handbook, module 201 "Frequency and Channel Assignments": S 240/221, X 880/749,
Ka 3344/3599). The uplink is the middle of each deep-space uplink allocation (S 2110-2120 MHz,
X 7145-7190 MHz, Ka 34200-34700 MHz), so the downlink falls in its allocation (S 2290-2300,
X 8400-8450, Ka 31800-32300 MHz). Dispersive delays (the ionosphere: 40.3 TEC / f²) and the
conversion of Doppler noise between Hz and mm/s depend on these.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

#: Band names a station's ``band`` may take.
BAND_NAMES = ("S", "X", "Ka")
#: The default band: X-band up and down, the DSN's deep-space workhorse.
DEFAULT_BAND = "X"


@dataclass(frozen=True, slots=True)
class Band:
    """One band: its name, uplink carrier f_T (Hz) and turnaround ratio M₂ = f_R / f_T."""

    name: str
    uplink_hz: float
    turnaround: Fraction

    @property
    def downlink_hz(self) -> float:
        """The coherent downlink carrier f_R = M₂ f_T, Hz."""
        return float(self.uplink_hz * self.turnaround)


#: The bands by name (810-005 module 201; module docstring).
BANDS = {
    "S": Band("S", 2115.0e6, Fraction(240, 221)),
    "X": Band("X", 7167.5e6, Fraction(880, 749)),
    "Ka": Band("Ka", 34450.0e6, Fraction(3344, 3599)),
}
