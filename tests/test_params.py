"""Energy parameters: the reference values of docs/energy-model.md, overrides, bad values."""

from __future__ import annotations

import pytest

from gtsp_bench.errors import InputError
from gtsp_bench.params import EnergyParams

REL = 1e-6


def test_reference_values_of_the_energy_model_doc():
    """Every derived quantity in the doc's reference table is reproduced (N = 20)."""
    p = EnergyParams()
    assert p.p_hover == pytest.approx(9.78905, rel=REL)
    assert p.p_move == pytest.approx(14.78905, rel=REL)
    assert p.flight_energy_per_m == pytest.approx(0.985937, rel=REL)
    assert p.p_los == pytest.approx(0.524334, rel=REL)
    assert p.path_loss_db == pytest.approx(118.7003, rel=REL)
    assert p.r_data == pytest.approx(5.448074e6, rel=REL)
    assert p.d0 == pytest.approx(87.7058, rel=REL)
    assert p.hover_time(20) == pytest.approx(27.89977, rel=REL)
    assert p.hover_energy(20) == pytest.approx(273.4638, rel=REL)
    assert p.upload_energy(20) == pytest.approx(3.51237, rel=REL)
    assert p.rx_energy == pytest.approx(0.4, rel=REL)
    assert p.p_ch_w == pytest.approx(0.12589, rel=1e-4)


def test_noise_power_is_density_times_bandwidth():
    """N_0 * B_width = -114 dBm."""
    assert EnergyParams().noise_w == pytest.approx(10 ** (-144 / 10), rel=1e-9)


def test_single_node_cluster_has_no_data_to_collect():
    """D_k = (N_k - 1) l is zero for a one-node cluster, so is its hovering."""
    p = EnergyParams()
    assert p.data_bits(1) == 0
    assert p.hover_energy(1) == 0
    assert p.upload_energy(1) == 0


def test_overrides_change_derived_values_and_round_trip():
    """An override is kept as a float, shows in overrides(), and moves derived quantities."""
    p = EnergyParams.from_mapping({"height": 100, "v_uav": 10})
    assert p.height == 100.0 and isinstance(p.height, float)
    assert p.overrides() == {"height": 100.0, "v_uav": 10.0}
    assert p.path_loss_db > EnergyParams().path_loss_db
    assert EnergyParams.from_mapping(p.overrides()) == p
    assert EnergyParams().overrides() == {}


def test_unknown_parameter_lists_valid_names():
    """An unknown name is rejected with the list of valid names."""
    with pytest.raises(InputError, match=r"unknown energy parameter 'hieght' \(valid: height,"):
        EnergyParams.from_mapping({"hieght": 10})


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("height", 0, "must be > 0"),
        ("p_com", -1, "must be >= 0"),
        ("mass", float("nan"), "must be finite"),
        ("mass", float("inf"), "must be finite"),
        ("bandwidth", "1e6", "must be a number"),
        ("bandwidth", True, "must be a number"),
    ],
)
def test_bad_values_are_rejected(name, value, message):
    """Non-numbers, non-finite values and out-of-range values raise InputError."""
    with pytest.raises(InputError, match=message):
        EnergyParams.from_mapping({name: value})


def test_dbm_parameters_may_be_negative():
    """Powers in dBm may be negative."""
    assert EnergyParams(p_ch_dbm=-3.0).p_ch_w == pytest.approx(10 ** (-3.3), rel=1e-9)
