"""Pictures of sweep files: the relaxation landscape with the Hopf line."""

from __future__ import annotations

import os
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

__all__ = ["plot_landscape"]


def plot_landscape(ds: xr.Dataset, path: str | os.PathLike, variable: str = "xi_inf") -> Path:
    """Log-log map of ``variable`` over (K/M, V) with the quasi-static Hopf line (K/M)_c(V) = g chi_c / D0.

    Points with a non-ok status are marked with grey crosses; the stick-slip side of the line (steady sliding
    unstable) is hatched.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    km, v_um = ds["K_over_M"].values, ds["V"].values * 1e6
    z = ds[variable].values.T  # rows: V, columns: K/M
    fig, ax = plt.subplots(figsize=(7.5, 5.5), dpi=110)
    finite = z[np.isfinite(z) & (z > 0)]
    norm = LogNorm(finite.min(), finite.max()) if finite.size and finite.max() > finite.min() else None
    mesh = ax.pcolormesh(km, v_um, np.ma.masked_invalid(z), shading="nearest", cmap="viridis", norm=norm)
    fig.colorbar(mesh, ax=ax, label=f"{ds[variable].attrs.get('long_name', variable)} [{ds[variable].units}]")
    unstable = ds["stable"].values.T == 0
    if unstable.any():
        ax.contourf(km, v_um, unstable.astype(float), levels=[0.5, 1.5], colors="none", hatches=["//"])
    scene_g_over_d0 = float(ds["K_over_M"][0] / ds["chi"][0])
    kc = ds["chi_c"].values * scene_g_over_d0
    ax.plot(kc, v_um, "w-", lw=2.2)
    ax.plot(kc, v_um, "r--", lw=1.6, label="Hopf line (linear, quasi-static)")
    failed = ds["status"].values.T != 0
    if failed.any():
        kk, vv = np.meshgrid(km, v_um)
        ax.plot(kk[failed], vv[failed], "x", color="0.5", ms=3, label="status != ok")
    ax.set(xscale="log", yscale="log", xlim=(km.min(), km.max()), ylim=(v_um.min(), v_um.max()),
           xlabel="K/M [s$^{-2}$]", ylabel="V [µm/s]")
    ax.set_title(_caption(ds), fontsize=9)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _caption(ds: xr.Dataset) -> str:
    params = tomllib.loads(ds.attrs["scene"]).get("params", {}) if "scene" in ds.attrs else {}
    shown = ", ".join(f"{k}={params[k]:g}" for k in ("A", "m1", "m2", "D0") if k in params)
    return f"stop scene, quasi-static model; {shown}\nhatched: steady sliding unstable (stick-slip)"
