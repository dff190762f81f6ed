"""Energy-model parameters of the paper (Zhu et al.), with the project's resolutions.

Every value is a field of :class:`EnergyParams`; the defaults are the paper's Table
"Simulation parameters" as resolved in ``docs/energy-model.md`` (see the README's table).
Derived quantities (hovering power, data rate, ...) are properties, so a user who overrides a
field gets consistent derived values.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from gtsp_bench.checks import is_number
from gtsp_bench.errors import InputError

#: Parameters that must be strictly positive; all others must be >= 0 except those in _ANY_SIGN.
_POSITIVE = frozenset({
    "height", "carrier_freq", "light_speed", "path_loss_exponent", "bandwidth", "mass", "gravity",
    "rotor_radius", "n_rotors", "air_density", "v_uav", "v_full", "eps_fs", "eps_mp",
    "message_bits",
})
#: Parameters in dB(m) that may take any sign.
_ANY_SIGN = frozenset({"p_ch_dbm", "noise_dbm_per_hz"})
#: Elevation angle tau in degrees: the UAV hovers straight above its head, so d_k = H.
ELEVATION_DEG = 90.0


@dataclass(frozen=True)
class EnergyParams:
    """Physical parameters of the UAV-IoT energy model (SI units unless the name says otherwise).

    Parameters
    ----------
    height
        Flight height H of the UAV in m; it hovers straight above the cluster head.
    carrier_freq, light_speed
        Carrier frequency f_c (Hz) and speed of light c (m/s).
    path_loss_exponent
        alpha in the mean path loss.
    los_eta, los_beta
        Environment constants eta and beta of the LoS probability.
    mu_los_db, mu_nlos_db
        Additional mean losses of LoS and NLoS links (dB).
    p_ch_dbm
        Transmit power P_CH of a cluster head (dBm, a total power).
    bandwidth
        B_width (Hz).
    noise_dbm_per_hz
        Noise density N_0 (dBm/Hz); the noise power is N_0 * B_width.
    mass, gravity
        m_tot (kg) and g (m/s^2).
    rotor_radius, n_rotors, air_density
        r_p (m), n_p and rho (kg/m^3).
    p_full, p_s
        Hardware power at full speed and when hovering (W).
    v_uav, v_full
        Flight speed and full speed (m/s).
    p_com
        UAV communication power (W).
    e_elec
        Radio electronics energy E_elec (J/bit).
    eps_fs, eps_mp
        Amplifier energies (J/bit/m^2 and J/bit/m^4).
    message_bits
        l, the message each member sends to its head (bits).
    """

    height: float = 50.0
    carrier_freq: float = 2e9
    light_speed: float = 3e8
    path_loss_exponent: float = 3.0
    los_eta: float = 10.0
    los_beta: float = 0.03
    mu_los_db: float = 1.0
    mu_nlos_db: float = 20.0
    p_ch_dbm: float = 21.0
    bandwidth: float = 1e6
    noise_dbm_per_hz: float = -174.0
    mass: float = 0.5
    gravity: float = 9.81
    rotor_radius: float = 0.2
    n_rotors: float = 4.0
    air_density: float = 1.225
    p_full: float = 5.0
    p_s: float = 0.0
    v_uav: float = 15.0
    v_full: float = 15.0
    p_com: float = 0.0126
    e_elec: float = 50e-9
    eps_fs: float = 10e-12
    eps_mp: float = 0.0013e-12
    message_bits: float = 8e6
    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if not is_number(value):
                raise InputError(f"energy parameter {f.name!r} must be a number, got {value!r}")
            try:
                finite = math.isfinite(value)
            except OverflowError:
                raise InputError(f"energy parameter {f.name!r} must be finite, got an integer "
                                 f"too large for a float") from None
            if not finite:
                raise InputError(f"energy parameter {f.name!r} must be finite, got {value!r}")
            if f.name in _POSITIVE and value <= 0:
                raise InputError(f"energy parameter {f.name!r} must be > 0, got {value!r}")
            if f.name not in _ANY_SIGN and value < 0:
                raise InputError(f"energy parameter {f.name!r} must be >= 0, got {value!r}")
            object.__setattr__(self, f.name, float(value))

    # ------------------------------------------------------------------ construction
    @classmethod
    def names(cls) -> list[str]:
        """Names of all settable parameters, in declaration order."""
        return [f.name for f in dataclasses.fields(cls)]

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any]) -> EnergyParams:
        """Build parameters from overrides, rejecting unknown names with the list of valid ones.

        Parameters
        ----------
        values
            Parameter name -> value; missing names keep their defaults.

        Raises
        ------
        InputError
            On an unknown name or an invalid value.
        """
        valid = cls.names()
        unknown = sorted(set(values) - set(valid))
        if unknown:
            raise InputError(
                f"unknown energy parameter {unknown[0]!r} (valid: {', '.join(valid)})"
            )
        return cls(**dict(values))

    def overrides(self) -> dict[str, float]:
        """The fields that differ from the defaults (what an instance file stores)."""
        default = EnergyParams()
        return {n: getattr(self, n) for n in self.names() if getattr(self, n) != getattr(default, n)}

    # ------------------------------------------------------------------ UAV power
    @cached_property
    def p_hover(self) -> float:
        """Rotor power of eq. (4) with v_UAV = 0, without P_s (W)."""
        return math.sqrt(
            (self.mass * self.gravity) ** 3
            / (2 * math.pi * self.rotor_radius**2 * self.n_rotors * self.air_density)
        )

    @cached_property
    def p_move(self) -> float:
        """Propulsion power of eq. (4) at speed v_uav (W)."""
        return self.p_hover + (self.p_full - self.p_s) / self.v_full * self.v_uav + self.p_s

    @cached_property
    def flight_energy_per_m(self) -> float:
        """UAV energy per metre flown, P_move / v_UAV (J/m)."""
        return self.p_move / self.v_uav

    # ------------------------------------------------------------------ channel
    @cached_property
    def p_los(self) -> float:
        """Probability of a line-of-sight link, eq. (1)."""
        return 1.0 / (1.0 + self.los_eta * math.exp(-self.los_beta * (ELEVATION_DEG - self.los_eta)))

    @cached_property
    def path_loss_db(self) -> float:
        """Mean path loss between head and UAV, eq. (2) (dB)."""
        fspl = 10 * self.path_loss_exponent * math.log10(
            4 * math.pi * self.carrier_freq * self.height / self.light_speed
        )
        return self.p_los * (fspl + self.mu_los_db) + (1 - self.p_los) * (fspl + self.mu_nlos_db)

    @cached_property
    def p_ch_w(self) -> float:
        """Head transmit power in W."""
        return 10 ** ((self.p_ch_dbm - 30) / 10)

    @cached_property
    def noise_w(self) -> float:
        """Noise power N_0 * B_width in W."""
        return 10 ** ((self.noise_dbm_per_hz - 30) / 10) * self.bandwidth

    @cached_property
    def r_data(self) -> float:
        """Head-to-UAV data rate of eq. (3) (bit/s)."""
        loss = 10 ** (self.path_loss_db / 10)
        return self.bandwidth * math.log2(1 + self.p_ch_w / (loss * self.noise_w))

    # ------------------------------------------------------------------ ground radio
    @cached_property
    def d0(self) -> float:
        """Distance threshold sqrt(eps_fs / eps_mp) of the first-order radio model (m)."""
        return math.sqrt(self.eps_fs / self.eps_mp)

    @cached_property
    def rx_energy(self) -> float:
        """Energy a head spends receiving one member's message, l * E_elec (J)."""
        return self.message_bits * self.e_elec

    # ------------------------------------------------------------------ per cluster
    def data_bits(self, n_nodes: int) -> float:
        """D_k = (N_k - 1) * l, the bits collected from a cluster of ``n_nodes`` nodes."""
        return max(n_nodes - 1, 0) * self.message_bits

    def hover_time(self, n_nodes: int) -> float:
        """Hovering time above a cluster of ``n_nodes`` nodes, D_k / r_data (s)."""
        return self.data_bits(n_nodes) / self.r_data

    def hover_energy(self, n_nodes: int) -> float:
        """E_{c_k}: UAV hovering plus communication energy at one cluster (J)."""
        return self.hover_time(n_nodes) * (self.p_hover + self.p_s + self.p_com)

    def upload_energy(self, n_nodes: int) -> float:
        """E_{b_k}: energy of the head uploading D_k bits to the UAV (J)."""
        return self.p_ch_w * self.hover_time(n_nodes)
