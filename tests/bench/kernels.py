"""The deep-space study under every OpenBLAS kernel this processor supports, side by side.

The results must not depend on the machine. Each supported kernel (``OPENBLAS_CORETYPE``:
SkylakeX needs avx512f, Haswell and Zen avx2, Sandybridge avx; a kernel the processor lacks
crashes, so the section reads the CPU flags first) runs, in its own child process,
``tapp simulate deep_space.toml`` → ``tapp process`` with
the example ``tapp3_deep_space.toml`` → ``tapp guide`` with the example ``tapp2_deep_space.toml``
(20,000 samples, serial). Comparisons, for every pair of kernels and as the largest over
the pairs, each with the quantity where it is largest:

* TAPP III on one tape (the first kernel's T13, processed under each kernel): every printed
  covariance, |ΔC_ij| / √(C_ii C_jj); and the whole chain (each kernel's own T13), the
  end-to-end figure;
* the T13 tapes themselves: the largest relative difference of a transition entry (U) and
  how many entries differ (TAPP I's share of the chain's spread: the exact answer on two
  tapes moves by what their U differ, through the conditioning of the data);
* TAPP II's derived statistics (each kernel's own chain): every number of the linear
  covariance and of the Monte Carlo (ΔV moments and percentiles, miss covariance, B-plane
  ellipse, fraction outside the corridor), relative to its size; means of zero-mean
  quantities and off-diagonal covariances relative to the σ's of their quantities.

Targets (issue 28): every printed covariance within 1e-9, TAPP II's linear statistics within
1e-8 (the Monte Carlo's are shown beside them, to the same target). The environment variable
is set in the children only: never in tests or CI.
"""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tapp.examples import FOLDER as EXAMPLES
from tests.bench.common import REPO_ROOT, Section, logger, markdown_table

NAME = "kernels"
#: OpenBLAS kernels and the CPU flag each needs (/proc/cpuinfo).
KERNELS = {"SkylakeX": "avx512f", "Haswell": "avx2", "Zen": "avx2", "Sandybridge": "avx"}
SAMPLES = 20_000
TARGET_COVARIANCE = 1e-9
TARGET_GUIDANCE = 1e-8
SCENARIOS = EXAMPLES
log = logger(NAME)


def supported_kernels() -> list[str]:
    """The kernels whose instruction set the processor has (Linux: /proc/cpuinfo flags)."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return []
    flags = set()
    for line in text.splitlines():
        if line.startswith("flags"):
            flags.update(line.split(":", 1)[1].split())
    return [k for k, flag in KERNELS.items() if flag in flags]


def _tapp(kernel: str, *args: str) -> None:
    env = dict(os.environ, OPENBLAS_CORETYPE=kernel)
    done = subprocess.run([sys.executable, "-m", "tapp.cli", *args], capture_output=True,
                          text=True, cwd=REPO_ROOT, env=env, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"tapp {args[0]} under {kernel} exited {done.returncode}: "
                           f"{done.stderr.strip()}")


def _covariances(path: Path) -> dict[tuple, tuple[str, np.ndarray]]:
    content = json.loads(path.read_text())
    return {(b["kind"], b["k"], e["omega"]): (f"{b['kind']} k={b['k']} {e['alias']}",
                                              np.array(e["matrix"]))
            for b in content["blocks"] for e in b["entities"] if "sigma" in e}


def _scaled(a: np.ndarray, b: np.ndarray) -> float:
    d = np.sqrt(np.abs(np.diagonal(a)))
    scale = np.outer(d, d)
    scale[scale == 0] = 1.0
    return float(np.max(np.abs(a - b) / scale)) if a.size else 0.0


def covariance_spread(paths: dict[str, Path]) -> dict[tuple[str, str], tuple[float, str]]:
    """Per pair of kernels: the largest scaled difference of any printed covariance, and the
    entity it is in."""
    runs = {k: _covariances(p) for k, p in paths.items()}
    out = {}
    for a, b in itertools.combinations(runs, 2):
        worst, where = 0.0, ""
        for key, (name, m) in runs[a].items():
            value = _scaled(m, runs[b][key][1])
            if value >= worst:
                worst, where = value, name
        out[(a, b)] = (worst, where)
    return out


def tape_spread(paths: dict[str, Path]) -> dict[tuple[str, str], tuple[float, int]]:
    """Per pair of kernels: the largest relative difference |ΔU_ij| / |U_ij| of an entry of
    the T13 tapes' transitions U, and how many entries differ."""
    from tapp.io.tape.t13_hdf5 import read_t13

    us = {k: read_t13(p).records.U for k, p in paths.items()}
    out = {}
    for a, b in itertools.combinations(us, 2):
        diff = np.abs(us[a] - us[b])
        differ = diff > 0
        rel = diff[differ] / np.maximum(np.abs(us[a][differ]), np.abs(us[b][differ]))
        out[(a, b)] = (float(rel.max(initial=0.0)), int(np.count_nonzero(differ)))
    return out


def _statistics(section: dict) -> list[tuple[str, float, float]]:
    """(name, value, scale) of every number of a guidance statistics section."""
    out = []
    for i, man in enumerate(section["manoeuvres"]):
        cov = np.array(man["dv_cov_km2_s2"])
        sd = np.sqrt(np.diag(cov))
        out += [(f"TCM-{i + 1} Δv mean {j}", v, sd[j]) for j, v in enumerate(man["dv_mean_km_s"])]
        out += [(f"TCM-{i + 1} Δv cov {j}{k}", cov[j, k], sd[j] * sd[k])
                for j in range(3) for k in range(3)]
        mag = man["magnitude"]
        out += [(f"TCM-{i + 1} Δv magnitude {name}", mag[name], abs(mag[name]))
                for name in ("mean_km_s", "sigma_km_s") if mag[name] is not None]
        out += [(f"TCM-{i + 1} Δv magnitude {p} %", v, abs(v))
                for p, v in (mag["percentiles_km_s"] or {}).items()]
    miss = np.array(section["miss_cov"])
    sd = np.sqrt(np.diag(miss))
    out += [(f"miss cov {j}{k}", miss[j, k], sd[j] * sd[k]) for j in range(len(sd))
            for k in range(len(sd))]
    out += [(f"miss mean {j}", v, sd[j]) for j, v in enumerate(section["miss_mean"])]
    out += [(f"B-plane {k}", v, abs(v)) for k, v in section["bplane_ellipse"].items()]
    out += [(f"outside corridor {k}", v, abs(v))
            for k, v in section["outside_corridor"].items() if v is not None]
    return out


def guidance_spread(paths: dict[str, Path]
                    ) -> dict[tuple[str, str], dict[str, tuple[float, str]]]:
    """Per pair of kernels and per method (linear, Monte Carlo): the largest relative
    difference and the statistic it is in."""
    stats = {k: json.loads(p.read_text()) for k, p in paths.items()}
    out = {}
    for a, b in itertools.combinations(stats, 2):
        out[(a, b)] = {}
        for method in ("linear", "monte_carlo"):
            worst, where = 0.0, ""
            for (name, x, scale), (_, y, _) in zip(_statistics(stats[a][method]),
                                                    _statistics(stats[b][method]), strict=True):
                rel = abs(x - y) / scale if scale > 0 else float(x != y)
                if rel >= worst:
                    worst, where = rel, name
            out[(a, b)][method] = (worst, where)
    return out


def _largest(per_pair: dict) -> tuple[float, str]:
    """The largest (value, where) over the pairs, where naming the pair."""
    (a, b), (value, where) = max(per_pair.items(), key=lambda item: item[1][0])
    return value, f"{a}/{b}: {where}"


def run() -> Section:
    """Run the deep-space study under each supported kernel; return the comparison."""
    kernels = supported_kernels()
    if len(kernels) < 2:
        md = ("## Results across OpenBLAS kernels\n\nSkipped: this processor supports "
              f"{len(kernels)} of the kernels {', '.join(KERNELS)} (CPU flags).")
        return Section(NAME, md, {"kernels": kernels})
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="tapp-kernels-") as tmp:
        folder = Path(tmp)
        for k in kernels:
            d = folder / k
            d.mkdir()
            log(f"{k}: simulate, process, guide")
            _tapp(k, "simulate", str(SCENARIOS / "deep_space.toml"), "-o", str(d / "ds.t13.h5"))
            _tapp(k, "process", str(d / "ds.t13.h5"), str(SCENARIOS / "tapp3_deep_space.toml"),
                  "--tape", str(d / "ds.t32.h5"), "--json", str(d / "own.json"))
            _tapp(k, "process", str(folder / kernels[0] / "ds.t13.h5"),
                  str(SCENARIOS / "tapp3_deep_space.toml"), "--json", str(d / "same.json"))
            _tapp(k, "guide", str(d / "ds.t32.h5"), str(SCENARIOS / "tapp2_deep_space.toml"),
                  "--samples", str(SAMPLES), "--seed", "1", "--serial", "--json",
                  str(d / "guide.json"))
        same = covariance_spread({k: folder / k / "same.json" for k in kernels})
        chain = covariance_spread({k: folder / k / "own.json" for k in kernels})
        tapes = tape_spread({k: folder / k / "ds.t13.h5" for k in kernels})
        guide = guidance_spread({k: folder / k / "guide.json" for k in kernels})
    wall = time.perf_counter() - start

    def ok(value: float, target: float) -> str:
        return "yes" if value <= target else "NO"

    summary = [("TAPP III covariances, one T13 tape", _largest(same), TARGET_COVARIANCE),
               ("TAPP III covariances, simulate + process per kernel", _largest(chain),
                TARGET_COVARIANCE)]
    summary += [(f"TAPP II {method.replace('_', ' ')} statistics",
                 _largest({pair: g[method] for pair, g in guide.items()}), TARGET_GUIDANCE)
                for method in ("linear", "monte_carlo")]
    rows = [[name, f"{value:.1e}", where, f"{target:g}", ok(value, target)]
            for name, (value, where), target in summary]
    pair_rows = [[f"{a} / {b}", f"{same[(a, b)][0]:.1e}", f"{chain[(a, b)][0]:.1e}",
                  f"{tapes[(a, b)][0]:.1e} ({tapes[(a, b)][1]})",
                  f"{guide[(a, b)]['linear'][0]:.1e}", f"{guide[(a, b)]['monte_carlo'][0]:.1e}"]
                 for a, b in same]
    md = "\n".join([
        "## Results across OpenBLAS kernels",
        "",
        f"The deep-space study (simulate, process, guide with {SAMPLES:,} samples) under each "
        f"OpenBLAS kernel this processor supports ({', '.join(kernels)}), in child processes "
        f"with OPENBLAS_CORETYPE set ({wall:.0f} s). Covariances on the scale √(C_ii C_jj); "
        "TAPP II statistics relative to their size (means of zero-mean quantities and "
        "off-diagonal covariances relative to the σ's of their quantities).",
        "",
        "Largest difference over every pair of kernels:",
        "",
        markdown_table(["compared", "largest difference", "where", "target", "within"], rows),
        "",
        "Per pair of kernels (T13 U: the largest relative difference of an entry, and the "
        "number of entries that differ):",
        "",
        markdown_table(["kernels", "TAPP III one tape", "TAPP III chain", "T13 U",
                        "TAPP II linear", "TAPP II Monte Carlo"], pair_rows),
    ])

    def pairs(per_pair: dict) -> dict[str, object]:
        return {f"{a}/{b}": value for (a, b), value in per_pair.items()}

    data = {"kernels": kernels, "samples": SAMPLES,
            "covariance_one_tape": _largest(same)[0], "covariance_chain": _largest(chain)[0],
            "per_pair": {"covariance_one_tape": pairs(same), "covariance_chain": pairs(chain),
                         "t13_U": pairs(tapes), "guidance": pairs(guide)},
            "guidance": {m: {"difference": v, "statistic": w} for m, (v, w) in
                         ((m, _largest({p: g[m] for p, g in guide.items()}))
                          for m in ("linear", "monte_carlo"))},
            "targets": {"covariance": TARGET_COVARIANCE, "guidance": TARGET_GUIDANCE}}
    return Section(NAME, md, data)


if __name__ == "__main__":
    print(run().markdown)
