//! Readable axis labels for mbgc's column and parameter names: symbols for the DEM parameters
//! (`mu_pp` -> "μ_pp"), words and units for the responses (`shear_angle` -> "shear angle (deg)").
//!
//! The labels use Greek letters and the superscripts ² and ³; the figures' "sans-serif" font
//! resolves to DejaVu Sans through fontconfig, which has them (SVG files carry the text as-is and
//! leave the font to the viewer).

/// The readable label of a column or parameter name, with its unit where it has one. Names mbgc
/// does not know keep their text, underscores replaced by spaces when the name is a plain
/// identifier (ASCII letters, digits and underscores); anything else, e.g. a label already made
/// readable by this function or by the caller, is returned unchanged, so applying it twice is
/// harmless.
pub fn axis_label(name: &str) -> String {
    let name = name.trim();
    if let Some(l) = known(name) {
        return l.to_string();
    }
    if let Some(k) = name.strip_prefix("flow_rate_t") {
        if is_digits(k) {
            return format!("flow rate, time bin {k} (kg/s)");
        }
    }
    for (prefix, place) in [
        ("repose_angle_top_", "top"),
        ("repose_angle_bottom_", "bottom"),
    ] {
        if let Some(k) = name.strip_prefix(prefix) {
            if is_digits(k) {
                return format!("angle of repose, {place} sector {k} (deg)");
            }
        }
    }
    if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return name.replace('_', " ").trim().to_string();
    }
    name.to_string()
}

/// A shorter form of [`axis_label`] for tight places (bar-chart categories, heat-map rows, the
/// panels of a corner plot): symbols instead of words where the words are long.
pub fn short_label(name: &str) -> String {
    match name.trim() {
        "ced_pp" => "CED_pp (J/m³)".into(),
        "ced_pw" => "CED_pw (J/m³)".into(),
        "sigma" => "σ (model error)".into(),
        n => axis_label(n),
    }
}

/// A title that starts with a column name followed by a colon ("shear_angle: Sobol indices")
/// with that name made readable ("shear angle (deg): Sobol indices"); other titles unchanged.
pub fn title_label(title: &str) -> String {
    match title.split_once(": ") {
        Some((name, rest))
            if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') =>
        {
            format!("{}: {rest}", axis_label(name))
        }
        _ => title.to_string(),
    }
}

fn is_digits(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_digit())
}

/// The labels of the names mbgc's experiments, parameter spaces and calibrations use.
fn known(name: &str) -> Option<&'static str> {
    Some(match name {
        // DEM parameters (examples/*.toml).
        "mu_pp" => "μ_pp",
        "mu_pw" => "μ_pw",
        "mu_r_pp" => "μ_r,pp",
        "mu_r_pw" => "μ_r,pw",
        "e_pp" => "e_pp",
        "e_pw" => "e_pw",
        "E_p" => "E_p (Pa)",
        "E_w" => "E_w (Pa)",
        "nu_p" => "ν_p",
        "rho_p" => "ρ_p (kg/m³)",
        "d50" => "d50 (mm)",
        "sigma_ln" => "σ_ln",
        "ced_pp" => "cohesion energy density, particle-particle (J/m³)",
        "ced_pw" => "cohesion energy density, particle-wall (J/m³)",
        // The relative model error a Bayesian calibration samples.
        "sigma" => "σ (relative model error)",
        // Shear box.
        "shear_angle" => "shear angle (deg)",
        "bulk_density" => "bulk density (kg/m³)",
        "flank_r2" => "R² of the flank line",
        "flank_curvature" => "flank curvature (relative to flank height)",
        "outflow_fraction" => "outflow fraction",
        // Hopper.
        "flow_rate" => "flow rate (kg/s)",
        "repose_angle_top" => "angle of repose, top (deg)",
        "repose_angle_bottom" => "angle of repose, bottom (deg)",
        "discharged_mass" => "discharged mass (kg)",
        "discharged_fraction" => "discharged fraction",
        "flow_R2" => "R² of the flow-rate fit",
        "beverloo_ratio" => "flow rate / Beverloo flow rate",
        "flow_bin_width" => "flow bin width (s)",
        "arch_held" => "particles held over the orifice",
        // Wall impact.
        "cnr" => "normal coefficient of restitution",
        "ctr" => "tangential coefficient of restitution",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_get_symbols_and_units() {
        for (name, label) in [
            ("mu_pp", "μ_pp"),
            ("mu_pw", "μ_pw"),
            ("mu_r_pp", "μ_r,pp"),
            ("mu_r_pw", "μ_r,pw"),
            ("e_pp", "e_pp"),
            ("e_pw", "e_pw"),
            ("E_p", "E_p (Pa)"),
            ("E_w", "E_w (Pa)"),
            ("nu_p", "ν_p"),
            ("rho_p", "ρ_p (kg/m³)"),
            ("d50", "d50 (mm)"),
            ("sigma_ln", "σ_ln"),
            ("sigma", "σ (relative model error)"),
        ] {
            assert_eq!(axis_label(name), label, "{name}");
        }
        assert!(axis_label("ced_pp").ends_with("(J/m³)"));
        assert!(axis_label("ced_pw").contains("particle-wall"));
    }

    #[test]
    fn responses_get_words_and_units() {
        assert_eq!(axis_label("shear_angle"), "shear angle (deg)");
        assert_eq!(axis_label("bulk_density"), "bulk density (kg/m³)");
        assert_eq!(axis_label("flow_rate"), "flow rate (kg/s)");
        assert_eq!(axis_label("flow_rate_t3"), "flow rate, time bin 3 (kg/s)");
        assert_eq!(
            axis_label("repose_angle_bottom"),
            "angle of repose, bottom (deg)"
        );
        assert_eq!(
            axis_label("repose_angle_top_2"),
            "angle of repose, top sector 2 (deg)"
        );
        assert_eq!(axis_label("flow_R2"), "R² of the flow-rate fit");
    }

    #[test]
    fn every_name_the_experiments_and_spaces_use_is_known() {
        use crate::experiments::hopper::{FLOW_BIN_NAMES, SECTOR_ANGLE_NAMES};
        use crate::experiments::shear_box::RESPONSES;
        let params = [
            "mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "e_pp", "e_pw", "E_p", "E_w", "nu_p", "rho_p",
            "d50", "sigma_ln", "ced_pp", "ced_pw",
        ];
        let hopper = [
            "flow_rate",
            "repose_angle_top",
            "repose_angle_bottom",
            "discharged_mass",
            "discharged_fraction",
            "flow_R2",
            "bulk_density",
            "beverloo_ratio",
            "flow_bin_width",
            "arch_held",
        ];
        for name in params
            .iter()
            .chain(&hopper)
            .chain(&RESPONSES)
            .chain(&["cnr", "ctr", "sigma"])
        {
            assert!(known(name).is_some(), "{name} has no readable label");
        }
        for name in FLOW_BIN_NAMES {
            assert!(axis_label(name).ends_with("(kg/s)"), "{name}");
        }
        for name in SECTOR_ANGLE_NAMES {
            assert!(axis_label(name).ends_with("(deg)"), "{name}");
        }
    }

    #[test]
    fn short_labels_and_titles() {
        assert_eq!(short_label("ced_pp"), "CED_pp (J/m³)");
        assert_eq!(short_label("mu_r_pp"), "μ_r,pp");
        assert_eq!(
            title_label("shear_angle: Sobol indices"),
            "shear angle (deg): Sobol indices"
        );
        assert_eq!(
            title_label("power-law exponents, 95 % intervals"),
            "power-law exponents, 95 % intervals"
        );
        assert_eq!(title_label("a b: c"), "a b: c");
    }

    #[test]
    fn unknown_names_lose_their_underscores_and_labels_stay() {
        assert_eq!(axis_label("some_new_response"), "some new response");
        assert_eq!(axis_label("  x_ "), "x");
        assert_eq!(axis_label("angle of repose / °"), "angle of repose / °");
        assert_eq!(axis_label(""), "");
        // Idempotent on its own output.
        for name in [
            "mu_r_pp",
            "shear_angle",
            "sigma",
            "flow_rate_t1",
            "new_name",
        ] {
            let once = axis_label(name);
            assert_eq!(axis_label(&once), once, "{name}");
        }
    }
}
