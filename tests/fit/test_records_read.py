"""Reading laboratory records (sweep.fit.records): files as laboratories write them, made from the scipy reference
(tests/reference_records.py) plus noise, irregular sampling and realistic headers; and bad records, one line each
naming the column."""

from __future__ import annotations

import numpy as np
import pytest
from reference_records import record_reference

from sweep.errors import InputError
from sweep.fit.records import Record, read_record

A, B, DC, MU0 = 0.01, 0.015, 1e-5, 0.6


@pytest.fixture(scope="module")
def vstep():
    """A 1 -> 10 um/s velocity step on a stiff machine, 800 irregular samples, noise 2e-4 in mu."""
    rng = np.random.default_rng(1)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 799))))
    mu, disp = record_reference(A, B, DC, MU0, 2e3, [1e-6, 1e-5], [20.0, 40.0], t)
    return t, mu + 2e-4 * rng.standard_normal(t.size), disp + 2e-9 * rng.standard_normal(t.size)


@pytest.fixture(scope="module")
def sawtooth():
    """Stick-slip: k = 480 1/m below k_c = (b - a)/Dc = 500 1/m, after a step to 10 um/s (a sawtooth in mu)."""
    rng = np.random.default_rng(2)
    t = np.sort(np.concatenate(([0.0], rng.uniform(0.0, 60.0, 1999))))
    mu, disp = record_reference(A, B, DC, MU0, 480.0, [1e-6, 1e-5], [10.0, 50.0], t)
    return t, mu + 1e-4 * rng.standard_normal(t.size), disp


def _write(path, text, encoding="utf-8"):
    path.write_bytes(text.encode(encoding))
    return path


def test_comma_file_with_stresses_preamble_and_trailing_commas(tmp_path, vstep):
    t, mu, disp = vstep
    sigma = 5e3 * (1 + 0.01 * np.sin(t))  # kPa, a normal stress that drifts: mu = tau/sigma per row
    rows = "\n".join(f"{a * 1e3:.3f},{d * 1e6:.6f},{m * s:.6f},{s:.4f}," for a, d, m, s in zip(t, disp, mu, sigma))
    path = _write(tmp_path / "run_p4966.csv", "% Biax run p4966, exported by the DAQ\n% k = 2000 1/m\n"
                  "# k = 2000 1/m\n\nTime (ms),LP Disp. (um),Shear Stress [kPa],Normal Stress [kPa],\n" + rows + "\n")
    rec = read_record(path)
    assert rec.name == "run_p4966" and rec.k == 2000.0 and rec.n == t.size
    np.testing.assert_allclose(rec.t, t, rtol=0, atol=1e-6)
    np.testing.assert_allclose(rec.displacement, disp, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rec.mu, mu, rtol=1e-5)


def test_blank_separated_units_row_latin1_micro(tmp_path, vstep):
    t, mu, disp = vstep
    rows = "\n".join(f"{a:.6f}   {d * 1e6:.6f}\t{m:.6f}" for a, d, m in zip(t, disp, mu))
    path = _write(tmp_path / "r.txt", "# sample = granite\ntime   lp_disp   mu\ns  µm  -\n" + rows, "latin-1")
    rec = read_record(path)
    assert rec.sample == "granite"
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-12)
    np.testing.assert_allclose(rec.mu, mu, atol=1e-6)


def test_unknown_headers_through_columns_mapping(tmp_path, vstep):
    t, mu, disp = vstep
    rows = "\n".join(f"{a / 60:.8f}\t{d * 1e3:.9f}\t{m:.6f}" for a, d, m in zip(t, disp, mu))
    path = _write(tmp_path / "zeit.tsv", "Zeit [min]\tWeg [mm]\tReibwert\n" + rows)
    with pytest.raises(InputError, match="no time column") as info:
        read_record(path)
    assert "\n" not in str(info.value)
    rec = read_record(path, columns={"time": "Zeit", "displacement": "Weg [mm]", "mu": "Reibwert"})
    np.testing.assert_allclose(rec.t, t, atol=1e-5)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-12)


def test_sawtooth_record_reads(tmp_path, sawtooth):
    t, mu, disp = sawtooth
    rows = "\n".join(f"{a:.6f};{d * 1e6:.6f};{m:.6f}".replace(".", ",") for a, d, m in zip(t, disp, mu))
    path = _write(tmp_path / "slip.csv", "Time (s);Load point displacement (um);Friction (-)\n" + rows)
    rec = read_record(path)
    assert np.ptp(rec.mu[t > 30]) > 0.05  # the stick-slip sawtooth is there, unsmoothed
    np.testing.assert_allclose(rec.mu, mu, atol=1e-6)


def _good(lines=200):
    t = np.linspace(0.0, 10.0, lines)
    return "\n".join(f"{a:.4f},{1e-6 * a * 1e6:.6f},{0.6:.4f}" for a in t)


@pytest.mark.parametrize("header, body, kwargs, needle", [
    ("time [s],disp [um]", None, {}, "no friction column"),
    ("time [s],mu", None, {}, "no load-point displacement"),
    ("time [s],disp [um],mu", None, {"columns": {"mu": "Friction"}}, "columns['mu'] = 'Friction' is not a column"),
    ("time,disp [um],mu", None, {}, "column 'time' (time) has no unit"),
    ("time [s],disp [furlong],mu", None, {}, "column 'disp' (displacement) has unit 'furlong'"),
    ("time [s],disp [um],mu", "0,0,0.6\n2,2,0.6\n1,1,0.6\n" + "\n".join(f"{3 + i},{3 + i},0.6" for i in range(20)), {},
     "column 'time' (time) is not strictly increasing: data row 3"),
    ("time [s],disp [um],mu", "\n".join(f"{i},{i},{'nan' if i == 7 else 0.6}" for i in range(20)), {},
     "column 'mu' (mu) has 1 NaN"),
    ("time [s],disp [um],mu", None, {"steps": [(0.0, 1e-6), (50.0, 1e-5)]}, "step 1 at t = 50 s is not in the data"),
])
def test_bad_records_one_line_naming_the_column(tmp_path, header, body, kwargs, needle):
    if body is None:
        n_cols = header.count(",") + 1
        body = "\n".join(",".join([f"{0.05 * i:.3f}", f"{0.05 * i:.3f}", "0.6"][:n_cols]) for i in range(200))
    path = _write(tmp_path / "bad.csv", header + "\n" + body + "\n")
    with pytest.raises(InputError) as info:
        read_record(path, **kwargs)
    msg = str(info.value)
    assert needle in msg and "\n" not in msg, msg


def test_record_checks_its_arrays():
    t = np.linspace(0.0, 1.0, 20)
    with pytest.raises(InputError, match="no load-point displacement or velocity column and no steps"):
        Record(t, np.full(20, 0.6))
    with pytest.raises(InputError, match="first > 0"):
        Record(t, np.full(20, 0.6), steps=[(0.0, 0.0), (0.5, 1e-6)])


def test_read_data_and_the_cli_config_take_a_record(tmp_path, vstep):
    """sweep.fit.read_data (hence ``sweep fit``'s [[data]] file = ...) hands a record file to read_record; a
    relaxation curve's file is still a Curve."""
    from sweep.fit import read_data

    t, mu, disp = vstep
    rows = "\n".join(f"{a:.6f},{d * 1e6:.6f},{m:.6f}" for a, d, m in zip(t, disp, mu))
    rec = read_data(_write(tmp_path / "rec.csv", "# k = 2 1/mm\ntime [s],lp_disp [um],mu\n" + rows), sample="s")
    assert isinstance(rec, Record) and rec.k == 2000.0 and rec.sample == "s"
    curve = read_data(_write(tmp_path / "c.csv", "# K_over_M = 2e5 s-2\n# V = 1 um/s\n# t: s\n# x: um\nt,x\n"
                             "0.1,0.01\n0.2,0.02\n0.4,0.03\n"))
    assert type(curve).__name__ == "Curve"
