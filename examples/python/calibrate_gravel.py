"""Calibrate the Gravel 8/16 example from Python, plot its posterior, predict over a grid.

Run from the repository's root after `pip install ./crates/mbgc-py matplotlib`:

    python examples/python/calibrate_gravel.py

It calibrates examples/gravel.toml against the shipped model (models/shear_box.json) with a
TMCMC posterior, writes gravel_posterior.png (the posterior of the sliding friction and the
particle density) and gravel_grid.png (the shear angle over a grid of sliding and rolling
friction at the calibrated point, with the measured value as a contour), and prints both.
"""

import matplotlib

matplotlib.use("Agg")  # files, no window

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

import mbgc

result = mbgc.calibrate("examples/gravel.toml", bayes=True, samples=2000)
print(result)

# The posterior: each free parameter's marginal and the two together.
post = result.posterior
fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
axes[0].hist(post["mu_pp"], bins=40, color="tab:blue")
axes[0].set_xlabel("mu_pp (sliding friction)")
axes[1].hist(post["rho_p"], bins=40, color="tab:orange")
axes[1].set_xlabel("rho_p (particle density, kg/m3)")
axes[2].scatter(post["mu_pp"], post["rho_p"], s=3, alpha=0.3)
best = result.best
axes[2].plot(best["mu_pp"], best["rho_p"], "r*", markersize=12, label="best optimum")
axes[2].set_xlabel("mu_pp")
axes[2].set_ylabel("rho_p")
axes[2].legend()
fig.suptitle(f"{result.material}: posterior (log evidence {result.log_evidence:.2f})")
fig.tight_layout()
fig.savefig("gravel_posterior.png", dpi=120)
print("wrote gravel_posterior.png")

# Predictions over a grid: the calibrated point with sliding and rolling friction varied.
model = mbgc.load_model()  # the shipped model, as the calibration used
mu = np.linspace(0.1, 0.9, 60)
mu_r = np.linspace(0.05, 0.95, 60)
mm, rr = np.meshgrid(mu, mu_r)
grid = pd.DataFrame({name: np.full(mm.size, value) for name, value in best.items()})
grid["mu_pp"] = mm.ravel()
grid["mu_r_pp"] = rr.ravel()
predicted = model.predict(grid)
angle = predicted["shear_angle"].to_numpy().reshape(mm.shape)

fig, ax = plt.subplots(figsize=(5.5, 4.5))
filled = ax.contourf(mm, rr, angle, levels=20, cmap="viridis")
fig.colorbar(filled, label="shear angle (deg)")
measured = float(result.measured.set_index("name").loc["shear_angle", "value"])
ax.contour(mm, rr, angle, levels=[measured], colors="white", linewidths=2)
ax.plot(best["mu_pp"], best["mu_r_pp"], "r*", markersize=12)
ax.set_xlabel("mu_pp")
ax.set_ylabel("mu_r_pp")
ax.set_title(f"shear angle; white: measured {measured} deg")
fig.tight_layout()
fig.savefig("gravel_grid.png", dpi=120)
print("wrote gravel_grid.png")
print(predicted[["mu_pp", "mu_r_pp", "shear_angle", "bulk_density"]].describe())
