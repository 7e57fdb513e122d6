//! Time step from the Rayleigh wave speed (Li et al. 2005; seed 004 Eq. 5).

/// Rayleigh time T_R = pi r sqrt(rho / G) / (0.1631 nu + 0.8766), G = E / (2 (1 + nu)): the time a
/// Rayleigh wave takes to cross a particle of radius r. Seed 004 runs at 0.25 T_R.
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
