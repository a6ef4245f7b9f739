"""EN 50318:2002 validation (docs/model.md, 'Verification'), with the reference data as given.

Each quantity at each speed is one test. Quantities the simulator misses are marked as known
failures with the measured value (strict: the mark must go when they start to pass). Nothing is
tuned to land in a range.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from catenary_env.validation import QUANTITIES, load_ranges, validate

# None since physics revision 3, whose modelling choices follow the reference model's definition
# (docs/model.md, 'Modelling choices'): all sixteen pass (0.5 m contact-wire elements, 1 ms, 10 spans,
# central 2 analysed). Revision 2 missed two at 250 km/h: σ = 25.81 N (26–31) and the actual maximum
# 168.75 N (175–210).
KNOWN_MISSES: dict[tuple[float, str], str] = {}


@pytest.fixture(scope="module")
def report():
    return validate((250.0, 300.0))


def _cases():
    for speed in (250.0, 300.0):
        for quantity in QUANTITIES:
            reason = KNOWN_MISSES.get((speed, quantity))
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            yield pytest.param(speed, quantity, marks=marks, id=f"{speed:g}kmh-{quantity}")


@pytest.mark.parametrize(("speed", "quantity"), list(_cases()))
def test_en50318_quantity_is_inside_its_accepted_range(report, speed, quantity):
    row = next(r for r in report.rows if r.speed_kmh == speed and r.quantity == quantity)
    assert row.low <= row.value <= row.high, (
        f"{quantity} at {speed:g} km/h = {row.value:.4g}, range {row.low}–{row.high}"
    )


def test_the_ranges_are_the_standards_table():
    ranges = load_ranges()
    assert ranges[300.0]["std"] == (32.0, 40.0)
    assert ranges[250.0]["mean"] == (110.0, 120.0)
    assert ranges[300.0]["max_support_uplift"] == (0.055, 0.065)


def test_the_table_is_the_one_recorded_in_the_readme_and_the_model_docs(report):
    # One formatter (ValidationReport.table) for catenary validate, the validation study and the report; the
    # recorded table is what it prints today (a change here is a change of the simulator's results).
    root = Path(__file__).resolve().parents[1]
    table = report.table()
    assert table.count("\n") == 17 and table.startswith("| speed (km/h) | quantity | value |")
    for document in ("README.md", "docs/model.md"):
        assert table in (root / document).read_text(encoding="utf-8"), document
