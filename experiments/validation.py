"""Study 1: validation against EN 50318:2002 at 250 and 300 km/h (table and figure).

    python -m experiments.validation [--out results]

The reference model is simulated as given (the presets' data); there is no quick setting because
the standard's model is itself small (10 spans).
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path

from catenary_env.validation import validate

from .common import DEFAULT_OUT, read_csv, run_cli, study_dir, write_csv
from .model_stamp import stamp_study

NAME = "validation"


@dataclass(frozen=True)
class Config:
    out: Path = DEFAULT_OUT
    full: bool = False  # the same model either way


def main(config: Config) -> Path:
    result = validate((250.0, 300.0))
    rows = [
        {
            "speed_kmh": r.speed_kmh,
            "quantity": r.quantity,
            "value": r.value,
            "low": r.low,
            "high": r.high,
            "passed": int(r.passed),
            "margin": r.margin,
        }
        for r in result.rows
    ]
    folder = study_dir(config.out, NAME)
    write_csv(folder / "en50318.csv", rows)
    stamp_study(folder, ("en50318-2002",))
    report(folder)
    return folder


def report(folder: Path) -> str:
    """Markdown table and a figure from the CSV (no simulation)."""
    rows = read_csv(folder / "en50318.csv")
    lines = ["| speed (km/h) | quantity | value | accepted range | result |", "|---|---|---|---|---|"]
    for r in rows:
        scale, unit = (
            (1e3, "mm")
            if r["quantity"] == "max_support_uplift"
            else (1.0, "%" if "percent" in r["quantity"] else "N")
        )
        verdict = "pass" if r["passed"] else f"FAIL (by {scale * r['margin']:.2f} {unit})"
        lines.append(
            f"| {r['speed_kmh']:g} | {r['quantity']} | {scale * r['value']:.2f} {unit} | "
            f"{scale * r['low']:g} – {scale * r['high']:g} | {verdict} |"
        )
    table = "\n".join(lines)
    (folder / "en50318.md").write_text(table + "\n", encoding="utf-8")
    _figure(rows, folder / "en50318.png")
    return table


def _figure(rows: list[dict], path: Path) -> None:
    from catenary_env.plots import pyplot

    plt = pyplot()
    quantities = [q for q in dict.fromkeys(r["quantity"] for r in rows) if q != "contact_loss_percent"]
    fig, axes = plt.subplots(1, len(quantities), figsize=(2.0 * len(quantities), 3.2))
    for ax, quantity in zip(axes, quantities, strict=True):
        for i, r in enumerate(r for r in rows if r["quantity"] == quantity):
            scale = 1e3 if quantity == "max_support_uplift" else 1.0
            ax.plot([i, i], [scale * r["low"], scale * r["high"]], color="0.7", lw=8, solid_capstyle="butt")
            ax.plot(i, scale * r["value"], "o", color="C2" if r["passed"] else "C3")
        ax.set_xticks([0, 1], ["250", "300"])
        ax.set_xlim(-0.6, 1.6)
        ax.set_title(
            quantity.replace("_", " ") + (" (mm)" if quantity == "max_support_uplift" else " (N)"), fontsize=8
        )
        ax.tick_params(labelsize=7)
    fig.suptitle(
        "EN 50318:2002: simulated value (dot) and accepted range (bar) at 250 and 300 km/h", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def cli(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (default: results)")
    args = parser.parse_args(argv)
    print(report(main(Config(out=args.out))))
    return 0


if __name__ == "__main__":
    raise SystemExit(run_cli(cli, "experiments.validation"))
