"""Laboratory records as real experiments write them (sweep.fit.records.read_record, sweep.fit.segments): files in
the styles of xlook/biax exports (a row counter, a units row, extra columns, CR LF), PSU's unit-suffixed names, a
European DAQ (semicolons, decimal commas, forces in kN), a velocity column, 1e5 rows; sampling that changes at a
step, noise in friction and in the load-point displacement. Each file is written in the test from the independent
scipy reference (tests/reference_records.py); the values read are checked against the values written."""

from __future__ import annotations

import numpy as np
import pytest
from reference_records import record_reference

from sweep.errors import InputError
from sweep.fit.records import Record, is_record_file, read_record
from sweep.fit.segments import record_steps

A, B, DC, MU0, K = 0.01, 0.015, 1e-5, 0.6, 2e3
VELOCITIES, DURATIONS = [1e-6, 1e-5], [20.0, 40.0]


def _times(rng):
    """10 Hz with jitter, 100 Hz for 5 s after the step (a DAQ that samples faster at a change), 10 Hz after."""
    t = np.concatenate([np.arange(0.0, 20.0, 0.1), np.arange(20.0, 25.0, 0.01), np.arange(25.0, 60.0, 0.1)])
    return np.round(t + 0.003 * rng.uniform(size=t.size) * (t > 0), 4)


@pytest.fixture(scope="module")
def vstep():
    """A 1 -> 10 um/s step on the reference: times, mu with 2e-4 noise, load-point displacement [m] with 50 nm."""
    rng = np.random.default_rng(21)
    t = _times(rng)
    mu, disp = record_reference(A, B, DC, MU0, K, VELOCITIES, DURATIONS, t)
    return t, mu + 2e-4 * rng.standard_normal(t.size), disp + 5e-8 * rng.standard_normal(t.size)


def _write(path, lines, newline="\n", encoding="utf-8"):
    path.write_bytes((newline.join(lines) + newline).encode(encoding))
    return path


def _steps_ok(rec, tol_t=0.3, rtol_v=0.01):
    steps = np.array(record_steps(rec))
    assert steps.shape == (2, 2), steps
    assert abs(steps[1, 0] - 20.0) < tol_t
    np.testing.assert_allclose(steps[:, 1], VELOCITIES, rtol=rtol_v)


def test_xlook_export_row_counter_units_row_crlf(tmp_path, vstep):
    """xlook/biax style: blank-separated, '%' preamble with a column table, a row counter, the units on a second
    header line (mic, sec, '.' for a dimensionless column), columns the fit does not use, CR LF line ends."""
    t, mu, disp = vstep
    sigma = 10.0 + 0.05 * np.sin(t)  # MPa
    head = ["% |Column|       Name|  Unit| Records|", f"% |     1|    LP_Disp|   mic| {t.size}|",
            "Exp: p4966 granite, 10 MPa", "Row    LP_Disp  Shr_stress  nor_disp  Nor_stress  Time  mu",
            ".      mic      MPa         micron    MPa         sec   ."]
    rows = [f"{i}  {d * 1e6:.4f}  {m * s:.5f}  {1000 - 0.01 * a:.3f}  {s:.5f}  {a:.4f}  {m:.6f}"
            for i, (a, d, m, s) in enumerate(zip(t, disp, mu, sigma))]
    path = _write(tmp_path / "p4966.txt", head + rows, newline="\r\n")
    assert is_record_file(path)
    rec = read_record(path)
    assert rec.n == t.size and rec.name == "p4966"
    np.testing.assert_allclose(rec.t, t, atol=1e-9)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-10)  # um -> m, not nor_disp
    np.testing.assert_allclose(rec.mu, mu, atol=1e-6)  # the mu column, not the stresses' ratio
    _steps_ok(rec)


def test_psu_unit_suffixed_names_title_line_and_stress_ratio(tmp_path, vstep):
    """PSU style: a title line, names carrying their unit as a suffix (time_s, lpdisp_um, shr_stress_mpa), a
    record number and a sampling-rate column, no mu: mu = shear / effective normal stress."""
    t, mu, disp = vstep
    effns = 25.0 * (1 + 0.01 * np.cos(t / 7))
    head = ["p5270 double-direct shear, Westerly gouge", "recnum,time_s,sampfreq_hz,lpdisp_um,shr_stress_mpa,effns_mpa"]
    rows = [f"{i},{a:.4f},{100 if 20 <= a < 25 else 10},{d * 1e6:.4f},{m * s:.6f},{s:.6f}"
            for i, (a, d, m, s) in enumerate(zip(t, disp, mu, effns))]
    rec = read_record(_write(tmp_path / "p5270.csv", head + rows))
    np.testing.assert_allclose(rec.mu, mu, atol=2e-7)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-10)
    _steps_ok(rec)


def test_european_daq_forces_in_kn_semicolons_decimal_commas(tmp_path, vstep):
    """Semicolons, decimal commas, latin-1, German names through ``columns``, shear and normal force in kN (their
    ratio is mu), a units override for a unit the file does not write."""
    t, mu, disp = vstep
    fn = 50.0 + 0.2 * np.sin(t)
    head = ["Zeit [s];Weg;Scherkraft [kN];Normalkraft [kN];Temperatur [°C]"]
    rows = [f"{a:.4f};{d * 1e3:.7f};{m * f:.5f};{f:.5f};21,5".replace(".", ",")
            for a, d, m, f in zip(t, disp, mu, fn)]
    path = _write(tmp_path / "versuch.csv", head + rows, encoding="latin-1")
    mapping = {"time": "Zeit", "displacement": "Weg", "shear": "Scherkraft", "normal": "Normalkraft"}
    with pytest.raises(InputError, match=r"column 'Weg' \(displacement\) has no unit.*units=") as info:
        read_record(path, columns=mapping)
    assert "\n" not in str(info.value)
    rec = read_record(path, columns=mapping, units={"displacement": "mm"})
    np.testing.assert_allclose(rec.mu, mu, atol=2e-7)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-10)
    _steps_ok(rec)


def test_velocity_column_tabs_units_in_parentheses(tmp_path, vstep):
    """A load-point velocity column (the servo's command) instead of the displacement."""
    t, mu, _ = vstep
    v = np.where(t < 20.0, 1.0, 10.0)  # um/s
    rows = [f"{a:.4f}\t{u:.3f}\t{m:.6f}" for a, u, m in zip(t, v, mu)]
    rec = read_record(_write(tmp_path / "vel.tsv", ["Time (s)\tV_lp (um/s)\tmu"] + rows))
    assert rec.displacement is None
    np.testing.assert_allclose(rec.velocity, v * 1e-6)
    _steps_ok(rec, tol_t=0.1, rtol_v=1e-3)  # the change falls between two samples 0.1 s apart


def test_a_displacement_that_counts_down_is_its_magnitude(vstep):
    t, mu, disp = vstep
    _steps_ok(Record(t, mu, displacement=5e-3 - disp))


def test_one_hundred_thousand_rows(tmp_path):
    """1e5 rows at 1 kHz (a velocity step, then a hold and a reslide), noise 0.1 um in the displacement written to
    1 nm: read (numpy's reader, not row by row) and segmented to the known steps."""
    rng = np.random.default_rng(3)
    t = np.arange(100_000) * 1e-3
    v = np.select([t < 30, t < 60, t < 80], [1e-6, 1e-5, 0.0], 1e-5)
    disp = np.concatenate(([0.0], np.cumsum(v[:-1] * 1e-3))) + 1e-7 * rng.standard_normal(t.size)
    rows = [f"{a:.3f}\t{d * 1e6:.3f}\t{0.6 + 1e-3 * r:.5f}" for a, d, r in zip(t, disp, rng.standard_normal(t.size))]
    rec = read_record(_write(tmp_path / "big.txt", ["Time [s]\tLP_Disp [um]\tmu [-]"] + rows))
    assert rec.n == 100_000
    steps = np.array(record_steps(rec))
    np.testing.assert_allclose(steps[1:, 0], [30.0, 60.0, 80.0], atol=0.05)
    np.testing.assert_allclose(steps[:, 1], [1e-6, 1e-5, 0.0, 1e-5], rtol=0.01, atol=0)


def test_a_record_that_starts_in_a_hold_says_where_to_cut_it(tmp_path, vstep):
    """A hold at the start is refused naming where the first slide begins; cut there plus a few Dc of slip (the
    ``t_start`` option), the record starts in steady sliding and its steps are found."""
    t, mu, disp = vstep
    pre = np.arange(-10.0, 0.0, 0.1)  # 10 s of hold before the slide, friction relaxing
    rows = [f"{a:.4f},{0.0:.5f},{MU0 - 0.003:.6f}" for a in pre] + \
           [f"{a:.4f},{d * 1e6:.5f},{m:.6f}" for a, d, m in zip(t, disp, mu)]
    path = _write(tmp_path / "hold_first.csv", ["time [s],lp_disp [um],mu"] + rows)
    with pytest.raises(InputError, match=r"starts in a hold .* from t = -10 to -?0(\.\d+)? s\).*t_start") as info:
        record_steps(read_record(path))
    assert "\n" not in str(info.value)
    rec = read_record(path, t_start=5.0)
    assert rec.t[0] >= 5.0 and rec.n == int(np.sum(t >= 5.0))
    _steps_ok(rec)
    given = read_record(path, steps=[(-10.0, 1e-6), (20.0, 1e-5)], t_start=5.0)
    assert given.steps == ((float(rec.t[0]), 1e-6), (20.0, 1e-5))


@pytest.mark.parametrize("lines, kwargs, needle", [
    (["time [s],lp_disp [um],mu"] + [f"{min(i, 30)},{i},0.6" for i in range(40)], {},
     "column 'time' (time) repeats a time: data row 32"),
    (["time [s],lp_disp [um],mu"] + [f"{i},{i},0.6" for i in range(40)] + ["40,40"], {},
     "data row 41 has 2 values, the header 3 (time, lp_disp, mu) (the last line, cut short: remove it)"),
    (["time [s],lp_disp [um],mu"], {}, "a header but no data rows"),
    (["time [s],lp_disp [um],shear [kN],normal [MPa]"] + [f"{i},{i},1,2" for i in range(40)], {},
     "column 'shear' (shear) is a force and 'normal' (normal) a stress"),
    (["time [s],lp_disp [um],mu"] + [f"{i},{i},0.6" for i in range(40)], {"t_start": 50.0},
     "t_start = 50 s is not in the data (time runs from 0 to 39 s)"),
    (["time [s],lp_disp [um],mu"] + [f"{i},{i},0.6" for i in range(40)], {"units": {"friction": "1"}},
     "units: 'friction' is not a record column"),
    (["time [s],lp_disp [um],mu"] + [f"{i},{i},0.6" for i in range(40)], {"units": {"time": "fortnight"}},
     "column 'time' (time) has unit 'fortnight'"),
])
def test_bad_real_files_one_line_naming_the_column(tmp_path, lines, kwargs, needle):
    path = _write(tmp_path / "bad.csv", lines)
    with pytest.raises(InputError) as info:
        read_record(path, **kwargs)
    msg = str(info.value)
    assert needle in msg and "\n" not in msg, msg


def test_sweep_fit_reads_a_record_with_unknown_headers_through_its_toml(tmp_path, vstep):
    """``sweep fit``: a [[data]] record file whose names the reader does not know, mapped with ``columns`` and a
    ``units`` override in the TOML: exit 0, and a, b, Dc, mu0 within 4 standard errors of the truth (the coverage
    of the intervals is tested on many draws in test_records_fit.py)."""
    import xarray as xr

    from sweep.cli import main

    t, mu, disp = vstep
    rows = [f"{a:.4f} {d * 1e6:.4f} {m:.6f}" for a, d, m in zip(t, disp, mu)]
    _write(tmp_path / "run7.dat", ["# k = 2 1/mm", "Zeit Weg Reibung"] + rows)
    (tmp_path / "fit.toml").write_text(
        'free = ["a", "b", "Dc", "mu0"]\n[params]\nA = 0.008\nm1 = 0.004\nm2 = 0.0\nD0 = 2e-5\nm0 = 0.6\n'
        '[[data]]\nfile = "run7.dat"\ncolumns = {time = "Zeit", displacement = "Weg", mu = "Reibung"}\n'
        'units = {time = "s", displacement = "um"}\n')
    out = tmp_path / "fit.nc"
    assert main(["fit", str(tmp_path / "fit.toml"), "-o", str(out), "-q"]) == 0
    with xr.open_dataset(out) as ds:
        for name, true in (("a", A), ("b", B), ("Dc", DC), ("mu0", MU0)):
            assert abs(float(ds[name][0]) - true) < 4 * float(ds[f"{name}_stderr"][0]), name
        assert int(ds["fit_status"][0]) == 0 and ds.sizes["datum"] == t.size


def test_spreadsheet_export_quotes_time_stamps_and_a_text_column(tmp_path, vstep):
    """A spreadsheet/LabVIEW export: every field quoted, the time as date-and-clock stamps (read as seconds from the
    first), a status column of words (never used: no error), the displacement in mm."""
    t, mu, disp = vstep
    start = np.datetime64("2024-03-05T14:02:07.250", "us")
    stamps = [str(start + np.timedelta64(int(round(a * 1e6)), "us")).replace("T", " ") for a in t]
    rows = [f'"{s}","{"RUN" if i % 7 else "HOLD?"}","{d * 1e3:.8f}","{m:.6f}"'
            for i, (s, d, m) in enumerate(zip(stamps, disp, mu))]
    rec = read_record(_write(tmp_path / "export.csv", ['"Timestamp","Status","LP Disp (mm)","Friction (-)"'] + rows),
                      columns={"time": "Timestamp"})
    np.testing.assert_allclose(rec.t - rec.t[0], t - t[0], atol=1e-6)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-11)
    np.testing.assert_allclose(rec.mu, mu, atol=1e-6)
    with pytest.raises(InputError, match=r"column 'Status' \(mu\) is not numbers \(e.g. 'HOLD\?', data row 1\)"):
        read_record(tmp_path / "export.csv", columns={"time": "Timestamp", "mu": "Status"})


def test_key_value_lines_above_the_header(tmp_path, vstep):
    """'Sampling rate,100' and 'Normal stress,10' lines above the header (a number among words): not data rows."""
    t, mu, disp = vstep
    rows = [f"{a:.4f},{d * 1e6:.4f},{m:.6f}" for a, d, m in zip(t, disp, mu)]
    rec = read_record(_write(tmp_path / "kv.csv", ["Sampling rate,100", "Normal stress,10", "Operator,JD",
                                                   "Time (s),LP_Disp (um),mu"] + rows))
    assert rec.n == t.size
    np.testing.assert_allclose(rec.t, t, atol=1e-9)


def test_names_with_blanks_in_a_blank_separated_file_and_negative_shear(tmp_path, vstep):
    """A blank-separated file whose names hold single blanks ('LP Disp (um)'), columns two blanks apart; shear
    stress counted negative (a sign convention): mu is its magnitude over the normal stress."""
    t, mu, disp = vstep
    rows = [f"{a:10.4f}  {d * 1e6:12.4f}  {-m * 5:12.6f}  {5.0:8.3f}" for a, d, m in zip(t, disp, mu)]
    head = "Time (s)  LP Disp (um)  Shear stress (MPa)  Normal stress (MPa)"
    rec = read_record(_write(tmp_path / "blanks.txt", [head] + rows))
    np.testing.assert_allclose(rec.mu, mu, atol=2e-7)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-10)


@pytest.mark.parametrize("extra, needle", [
    ('columns = {time = "Zeit"}', "columns['time'] = 'Zeit' is not a column of the file"),
    ('t_begin = 5.0', "unknown key(s) ['t_begin']"),
    ('t_start = 99.0', "t_start = 99 s is not in the data"),
])
def test_sweep_fit_refuses_a_bad_record_option_in_one_line(tmp_path, capsys, vstep, extra, needle):
    from sweep.cli import main

    t, mu, disp = vstep
    _write(tmp_path / "r.csv", ["time [s],lp_disp [um],mu"] + [f"{a:.4f},{d * 1e6:.4f},{m:.6f}"
                                                              for a, d, m in zip(t, disp, mu)])
    (tmp_path / "fit.toml").write_text(f'free = ["a", "b"]\n[[data]]\nfile = "r.csv"\n{extra}\n')
    assert main(["fit", str(tmp_path / "fit.toml"), "-o", str(tmp_path / "o.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and err.count("\n") == 0, err


def test_a_spreadsheets_unicode_text_utf16_tabs(tmp_path, vstep):
    """A spreadsheet's 'Unicode text': UTF-16 with its byte-order mark, tab-separated, µm in the header."""
    t, mu, disp = vstep
    rows = [f"{a:.4f}\t{d * 1e6:.4f}\t{m:.6f}" for a, d, m in zip(t, disp, mu)]
    path = _write(tmp_path / "unicode.txt", ["Time [s]\tLP_Disp [µm]\tµ"] + rows, newline="\r\n", encoding="utf-16")
    assert is_record_file(path)
    rec = read_record(path)
    np.testing.assert_allclose(rec.displacement, disp, atol=1e-10)
    np.testing.assert_allclose(rec.mu, mu, atol=1e-6)
