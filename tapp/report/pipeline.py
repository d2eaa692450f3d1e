"""The report of a pipeline run (``DIR/report.md``) and its plots (``DIR/plots/``).

Sections: the inputs and the Earth orientation; TAPP I (what was simulated); TAPP III (the
fit- and real-world σ of the miss at each recycle, i.e. at each midcourse time, and an excerpt
of the O3 printout); TAPP II (the guidance study's tables, Monte Carlo beside linear
covariance); the plots (σ against time and the B-plane ellipses of TAPP III, the final-miss
scatter and the ΔV histograms of TAPP II).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from tapp.constants import SECONDS_PER_DAY
from tapp.report import BPLANE_PNG, HISTOGRAM_PNG, RIC_PNG, SCATTER_PNG, SIGMA_PNG
from tapp.report.markdown import table

if TYPE_CHECKING:
    from tapp.io.tape.t13 import T13Header

#: Lines of the O3 printout quoted in the report (the whole printout is o3.txt).
O3_EXCERPT_LINES = 40


def recycle_sigma_table(content: dict) -> str:
    """Markdown table of the miss σ, fit / real, at each recycle of a ``run_dict``, with the
    significant digits those covariances hold."""
    miss = content["history"]["miss"]
    rows = [[r["number"], r["k"], f"{r['t_s'] / SECONDS_PER_DAY:.3f}",
             *(f"{f:.4g} / {g:.4g}" for f, g in zip(r["miss_sigma_fit"], r["miss_sigma_real"],
                                                     strict=True)), f"~{r['digits']:.1f}"]
            for r in content["recycles"]]
    return table(["recycle", "k", "t (d)", *(f"σ {m} fit / real" for m in miss),
                  "digits held"], rows)


def bplane_ellipse_table(content: dict) -> str:
    """Markdown table of the 1σ B-plane dispersion ellipses, fit / real, at each print and
    recycle time of a ``run_dict`` (empty when the miss set has no B·T and B·R)."""

    def pair(row: dict, key: str, fmt: str) -> str:
        fit, real = row["bplane_ellipse_fit"], row["bplane_ellipse_real"]
        left = "-" if fit is None else format(fit["sigma1"][key] if key != "angle_deg"
                                              else fit[key], fmt)
        return f"{left} / {format(real['sigma1'][key] if key != 'angle_deg' else real[key], fmt)}"

    rows = [[h["kind"], h["k"], f"{h['t_s'] / SECONDS_PER_DAY:.3f}",
             pair(h, "semi_major_km", ".4g"), pair(h, "semi_minor_km", ".4g"),
             pair(h, "angle_deg", "+.2f")]
            for h in content["history"]["rows"] if h.get("bplane_ellipse_real")]
    if not rows:
        return ""
    return table(["time", "k", "t (d)", "1σ semi-major (km) fit / real",
                  "1σ semi-minor (km) fit / real", "angle from T towards R (deg) fit / real"],
                 rows)


def ric_sigma_table(content: dict) -> str:
    """Markdown table of the orbit's position σ along R, I, C (m), fit / real, at each print
    and recycle time of a ``run_dict`` (empty unless the deck asked for RIC axes)."""
    rows = [[h["kind"], h["k"], f"{h['t_s'] / SECONDS_PER_DAY:.3f}",
             *(("-" if h["ric_sigma_fit"] is None else f"{1e3 * h['ric_sigma_fit'][i]:.4g}")
               + f" / {1e3 * h['ric_sigma_real'][i]:.4g}" for i in range(3))]
            for h in content["history"]["rows"] if h.get("ric_sigma_real")]
    if not rows:
        return ""
    return table(["time", "k", "t (d)", *(f"σ {a} (m) fit / real" for a in
                                          ("radial R", "in-track I", "cross-track C"))], rows)


def _plots(folder: Path, run, header: T13Header, guidance, title: str) -> list[Path]:
    from tapp.report.guidance import plot_bplane_scatter, plot_dv_histograms
    from tapp.report.processor import (
        bplane_rows,
        plot_bplane_ellipses,
        plot_ric_history,
        plot_sigma_history,
        ric_rows,
    )

    folder.mkdir(exist_ok=True)
    miss = tuple(header.miss.name)
    out = [plot_sigma_history(run.history, run.history_labels, folder / SIGMA_PNG,
                              f"{title}: σ, fit vs real world")]
    if ric_rows(run.history):
        out.append(plot_ric_history(run.history, folder / RIC_PNG,
                                    f"{title}: σ in RIC axes, fit vs real world"))
    if bplane_rows(run.history, miss):
        out.append(plot_bplane_ellipses(run.history, miss, folder / BPLANE_PNG,
                                        f"{title}: B-plane 1σ/3σ, fit vs real"))
        out.append(plot_bplane_scatter(guidance, folder / SCATTER_PNG,
                                       f"{title}: final B-plane miss"))
    out.append(plot_dv_histograms(guidance, folder / HISTOGRAM_PNG,
                                  f"{title}: ΔV per manoeuvre"))
    return out


def ellipse_and_ric_sections(content: dict) -> list[str]:
    """Markdown lines of the B-plane ellipse and RIC σ tables of a ``run_dict``, each with
    its caption, leaving out a table that is empty."""
    tables = (("1σ B-plane dispersion ellipses, fit / real (3σ: three times the semi-axes):",
               bplane_ellipse_table(content)),
              ("σ of the orbit position in radial / in-track / cross-track axes of the nominal "
               "state, fit / real:", ric_sigma_table(content)))
    return [line for caption, markdown in tables if markdown
            for line in (caption, "", markdown, "")]


def write_report(folder: Path, pipeline, run, header: T13Header, content: dict,
                 guidance, observations: int, wall_s: dict[str, float], plots: bool = True
                 ) -> Path:
    """Write ``folder/report.md`` (and the plots into ``folder/plots`` when asked)."""
    from tapp.report.guidance import guidance_markdown

    title = pipeline.title or header.iden
    prov = header.provenance
    o3 = (folder / "o3.txt").read_text("utf-8").splitlines()[:O3_EXCERPT_LINES]
    images = _plots(folder / "plots", run, header, guidance, title) if plots else []
    tapp2 = guidance_markdown(guidance).replace("\n## ", "\n### ").replace(
        "# TAPP II", "## TAPP II", 1)
    lines = [
        f"# Pipeline: {title}", "",
        f"Pipeline file `{pipeline.source}`: scenario `{pipeline.scenario.source}`, deck "
        f"`{pipeline.deck.source}`, guidance `{pipeline.guidance.source}`. Earth orientation "
        f"{prov.get('earth_orientation', 'gmst')}"
        + (f" (EOP {prov['eop']})" if prov.get("eop") else "") + ". Wall time: "
        + ", ".join(f"{k} {v:.2f} s" for k, v in wall_s.items()) + ".", "",
        "## TAPP I: tracking simulation (`run.t13.h5`)", "",
        f"{header.iden}: n_o = {header.n_o}, n_p = {header.n_p}, n_m = {header.n_m}, "
        f"{observations} observations in {header.passes.station.size} passes by "
        f"{header.n_ts} stations.", "",
        "## TAPP III: fit world vs real world (`o3.txt`, `process.json`, `run.t32.h5`)", "",
        "σ of the miss at each recycle (the midcourse times handed to TAPP II), fit world / "
        "real world:", "", recycle_sigma_table(content), "",
        *ellipse_and_ric_sections(content),
        f"The first {O3_EXCERPT_LINES} lines of the O3 printout:", "", "```",
        *o3, "```", "",
        tapp2.rstrip(), "",
    ]
    if images:
        lines += ["## Plots", "", *(f"![{p.stem}](plots/{p.name})" for p in images), ""]
    path = folder / "report.md"
    path.write_text("\n".join(lines), "utf-8")
    return path
