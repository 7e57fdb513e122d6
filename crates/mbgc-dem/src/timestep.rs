//! Time step from the Rayleigh wave speed (Li et al. 2005; seed 004 Eq. 5).

/// Rayleigh time T_R = pi r sqrt(rho / G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)), in s:
/// the time a Rayleigh surface wave, of speed v_R = (0.1631 nu + 0.8766) sqrt(G / rho), takes to
/// run half round a sphere of radius r (pi r). Contact forces travel at about that speed, so an
/// explicit step must be a fraction of T_R of the smallest particle: seed 004 runs at 0.25 T_R,
/// seed 000 uses 0.1..0.2 T_R, and [`crate::Simulation::new`] refuses more than the scene's
/// `max_dt_fraction`.
///
/// `radius` in m, `density` in kg/m^3, `youngs_modulus` in Pa, `poisson` dimensionless in
/// (-1, 0.5].
///
/// ```
/// // A 1 mm sphere, rho = 2500 kg/m^3, E = 25 MPa, nu = 0.25: G = 25e6 / 2.5 = 1e7 Pa,
/// // sqrt(rho / G) = sqrt(2.5e-4) = 0.0158114 s/m, 0.1631 * 0.25 + 0.8766 = 0.917375, so
/// // T_R = pi * 1e-3 * 0.0158114 / 0.917375 = 5.41468e-5 s.
/// let t = mbgc_dem::timestep::rayleigh_time(1e-3, 2500.0, 25e6, 0.25);
/// assert!((t - 5.41468e-5).abs() < 1e-5 * t, "{t}");
/// // T_R scales with r and with sqrt(rho / E): halving the size halves the step.
/// let half = mbgc_dem::timestep::rayleigh_time(0.5e-3, 2500.0, 25e6, 0.25);
/// assert!((half / t - 0.5).abs() < 1e-12);
/// ```
pub fn rayleigh_time(radius: f64, density: f64, youngs_modulus: f64, poisson: f64) -> f64 {
    let g = youngs_modulus / (2.0 * (1.0 + poisson));
    std::f64::consts::PI * radius * (density / g).sqrt() / (0.1631 * poisson + 0.8766)
}

#[cfg(test)]
mod tests {
    #[test]
    fn rayleigh_time_of_the_benchmark_scene() {
        // r = 3.75 mm, rho = 2600, E = 5e7, nu = 0.3: G = 1.923e7 Pa.
        let t = super::rayleigh_time(3.75e-3, 2600.0, 5e7, 0.3);
        let g: f64 = 5e7 / 2.6;
        let want = std::f64::consts::PI * 3.75e-3 * (2600.0 / g).sqrt() / (0.1631 * 0.3 + 0.8766);
        assert!(
            (t - want).abs() < 1e-18 && (t - 1.48e-4).abs() < 1e-6,
            "{t}"
        );
    }
}
