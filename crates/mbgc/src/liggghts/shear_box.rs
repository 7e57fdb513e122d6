//! The shear box (seed 004) as a LIGGGHTS 3.8 deck that replays a recorded mbgc run: the data
//! file with mbgc's initial particles, the five walls as STL meshes, and an input script with
//! mbgc's schedule, so that both codes start from the identical configuration and do the same
//! things at the same steps: fill, strike off at the rim, relax, remove the flap, and remove what
//! fell below the floor every chunk.
//!
//! `delete_atoms` must not compress the atom ids: LIGGGHTS keys the contact history by partner
//! id, and renumbering after every deletion scrambled the histories of the remaining contacts
//! (the replayed shear angle came out 2-3 degrees low until `compress no`).
//!
//! The contact law is the recorded run's model class, effect by effect (`EffectSpec::liggghts`).
//! With `sjkr` both codes cap the tangential spring and the EPSD2 torque with the normal force
//! before cohesion (LIGGGHTS 3.8's default, `tangential_reduce off`; mbgc's choice, see
//! `dem/contact/law.rs`). They still differ in one thing: with cohesion on, mbgc keeps the stored
//! rolling torque in the tangent plane, LIGGGHTS does not (its cohesive beds gain rotational
//! energy, tests/cohesion.rs).

use std::fmt::Write as _;
use std::path::Path;

use super::mesh::rect_stl;
use super::number::num;
use crate::error::{write_atomic, Error, Result};
use crate::experiments::shear_box::RunRecord;
use crate::experiments::ParamSet;
use mbgc_dem::contact::{CohesionKind, ModelClass, Slot};

/// Name of the input script written by [`write_deck`].
pub const INPUT: &str = "in.shear_box";
/// Name of the log LIGGGHTS writes for it.
pub const LOG: &str = "log.shear_box";
/// Dumps the deck writes: after the fill and at the end.
pub const FILLED_DUMP: &str = "filled.dump";
/// Dump at the end of the replay, after the outflow.
pub const FINAL_DUMP: &str = "final.dump";

/// The contact law in LIGGGHTS' words: the models (after `pair_style gran` and `wall/gran`) and
/// the settings, which LIGGGHTS reads only at the end of the command (after the mesh or
/// primitive of a wall).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GranModel {
    /// The model keywords in the order LIGGGHTS accepts them, e.g.
    /// `model hertz tangential history rolling_friction epsd2`.
    pub models: String,
    /// Empty, or starting with a space.
    pub settings: String,
}

/// The order in which LIGGGHTS 3.8 accepts the models ("wrong keyword order" otherwise).
const LIGGGHTS_ORDER: [Slot; 4] = [
    Slot::Normal,
    Slot::Tangential,
    Slot::Cohesion,
    Slot::Rolling,
];

/// Refuses what LIGGGHTS 3.8 cannot replay identically, naming the effect.
pub fn gran_model(class: &ModelClass) -> Result<GranModel> {
    let effects = class.effects();
    for e in &effects {
        if e.liggghts.is_none() {
            return Err(Error::invalid(format!(
                "model class {class}: LIGGGHTS 3.8 has no {} '{}' ({}), so the run cannot be \
                 replayed there",
                e.slot.label(),
                e.name,
                e.what
            )));
        }
    }
    if class.limit_force {
        // LIGGGHTS' limitForce clips the force but keeps the damping of the unclipped law, so
        // its restitution differs from mbgc's, which re-solves the damping.
        return Err(Error::invalid(format!(
            "model class {class}: `limit-force` re-solves the damping so that e stays the \
             restitution; LIGGGHTS 3.8's `limitForce on` does not, so the run cannot be replayed \
             identically"
        )));
    }
    let models = LIGGGHTS_ORDER
        .iter()
        .flat_map(|slot| effects.iter().filter(move |e| e.slot == *slot))
        .filter_map(|e| e.liggghts)
        .collect::<Vec<_>>()
        .join(" ");
    // LIGGGHTS' defaults are mbgc's law; a setting that mbgc's law needed would go here.
    let settings = String::new();
    Ok(GranModel { models, settings })
}

/// Writes the data file, the wall meshes and the input script into `dir`, with the contact law
/// of the recorded run.
pub fn write_deck(dir: &Path, p: &ParamSet, rec: &RunRecord) -> Result<()> {
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
    let GranModel { models, settings } = gran_model(&rec.class)?;
    let [l, w, h] = rec.layout.size;
    let rho = get("rho_p")?;
    let (lo, hi) = rec.domain;
    let mut data = String::from("LIGGGHTS data file written by mbgc (shear box)\n\n");
    let _ = writeln!(
        data,
        "{} atoms\n2 atom types\n",
        rec.initial_positions.len()
    );
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let _ = writeln!(data, "{} {} {axis}lo {axis}hi", num(lo[k]), num(hi[k]));
    }
    let _ = writeln!(data, "\nAtoms\n");
    for (i, (x, d)) in rec
        .initial_positions
        .iter()
        .zip(&rec.layout.diameters)
        .enumerate()
    {
        let _ = writeln!(
            data,
            "{} 1 {} {} {} {} {}",
            i + 1,
            num(*d),
            num(rho),
            num(x[0]),
            num(x[1]),
            num(x[2])
        );
    }
    write_atomic(&dir.join("data.shear_box"), data.as_bytes())?;
    let wall_h = hi[2] - 1e-9;
    write_box_walls(dir, l, w, wall_h)?;
    let n_chunks = rec.flow_steps.div_ceil(rec.chunk);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# mbgc shear box replay. Type 1: particles, type 2: walls."
    );
    let _ = writeln!(s, "units si\natom_style granular\natom_modify map array\nboundary f f f\nnewton off\ncommunicate single vel yes");
    let _ = writeln!(
        s,
        "read_data data.shear_box\nneighbor {} bin\nneigh_modify delay 0\n",
        num(rec.skin)
    );
    write_contact_properties(&mut s, p)?;
    write_cohesion(&mut s, p, &rec.class)?;
    s.push('\n');
    write_box_physics(&mut s, &models, &settings, rec.dt, l);
    let _ = writeln!(
        s,
        "fix integrate all nve/sphere\nthermo 2000\nthermo_modify lost ignore norm no\n"
    );
    let _ = writeln!(s, "run {}", rec.fill_steps);
    let _ = writeln!(
        s,
        "region above block INF INF INF INF {} INF units box\ndelete_atoms region above compress no",
        num(h)
    );
    let _ = writeln!(s, "run {}", rec.relax_steps);
    let _ = writeln!(s, "write_dump all custom {FILLED_DUMP} id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"");
    let _ = writeln!(s, "unfix flapwall");
    let _ = writeln!(
        s,
        "region below block INF INF INF INF INF {} units box",
        num(rec.removal_height)
    );
    let _ = writeln!(s, "variable i loop {n_chunks}\nlabel flow\nrun {}\ndelete_atoms region below compress no\nnext i\njump SELF flow", rec.chunk);
    let _ = writeln!(s, "write_dump all custom {FINAL_DUMP} id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"");
    write_atomic(&dir.join(INPUT), s.as_bytes())
}

/// The names of the box's fixed walls, in the order [`write_box_walls`] writes them.
/// The contact properties of particles (type 1) and walls (type 2), fixes m1-m5: moduli,
/// Poisson ratio, restitution, friction and rolling friction, the wall-wall entries set to the
/// particle-wall ones. Shared by the replay and the self-filling deck.
pub(crate) fn write_contact_properties(s: &mut String, p: &ParamSet) -> Result<()> {
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
    let pair = |pp: f64, pw: f64| format!("{} {} {} {}", num(pp), num(pw), num(pw), num(pw));
    let nu = get("nu_p")?;
    let _ = writeln!(
        s,
        "fix m1 all property/global youngsModulus peratomtype {} {}",
        num(get("E_p")?),
        num(get("E_w")?)
    );
    let _ = writeln!(
        s,
        "fix m2 all property/global poissonsRatio peratomtype {} {}",
        num(nu),
        num(nu)
    );
    for (fix, name, pp, pw) in [
        ("m3", "coefficientRestitution", "e_pp", "e_pw"),
        ("m4", "coefficientFriction", "mu_pp", "mu_pw"),
        ("m5", "coefficientRollingFriction", "mu_r_pp", "mu_r_pw"),
    ] {
        let _ = writeln!(
            s,
            "fix {fix} all property/global {name} peratomtypepair 2 {}",
            pair(get(pp)?, get(pw)?)
        );
    }
    Ok(())
}

/// The cohesion energy densities (fix m6) when the class has SJKR cohesion.
pub(crate) fn write_cohesion(s: &mut String, p: &ParamSet, class: &ModelClass) -> Result<()> {
    if class.cohesion != CohesionKind::Sjkr {
        return Ok(());
    }
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
    let (ced_pp, ced_pw) = (get("ced_pp")?, get("ced_pw")?);
    let _ = writeln!(
        s,
        "fix m6 all property/global cohesionEnergyDensity peratomtypepair 2 {} {} {} {}",
        num(ced_pp),
        num(ced_pw),
        num(ced_pw),
        num(ced_pw)
    );
    Ok(())
}

/// The pair style, time step, gravity, the box's wall meshes and the flap: the part of a shear-box
/// deck that the replay and the self-filling deck share.
pub(crate) fn write_box_physics(s: &mut String, models: &str, settings: &str, dt: f64, l: f64) {
    let _ = writeln!(
        s,
        "pair_style gran {models}{settings}\npair_coeff * *\ntimestep {}",
        num(dt)
    );
    let _ = writeln!(s, "fix gravity all gravity 9.81 vector 0.0 0.0 -1.0");
    for name in BOX_WALLS {
        let _ = writeln!(s, "fix {name} all mesh/surface file {name}.stl type 2");
    }
    let _ = writeln!(
        s,
        "fix box all wall/gran {models} mesh n_meshes 4 meshes floor back side_lo side_hi{settings}"
    );
    // LIGGGHTS takes one mesh wall fix only; the flap is a plane, which inside the box acts as
    // the flap rectangle does, and is gone before anything reaches beyond it.
    let _ = writeln!(
        s,
        "fix flapwall all wall/gran {models} primitive type 2 xplane {}{settings}",
        num(l)
    );
}

pub(crate) const BOX_WALLS: [&str; 4] = ["floor", "back", "side_lo", "side_hi"];

/// The box's fixed walls (floor, back, two sides; the flap is a plane of its own) as STL meshes
/// `wall_h` high, written into `dir`.
pub(crate) fn write_box_walls(dir: &Path, l: f64, w: f64, wall_h: f64) -> Result<()> {
    let walls = [
        ("floor", [0.0, 0.0, 0.0], [l, 0.0, 0.0], [0.0, w, 0.0]),
        ("back", [0.0, 0.0, 0.0], [0.0, w, 0.0], [0.0, 0.0, wall_h]),
        (
            "side_lo",
            [0.0, 0.0, 0.0],
            [l, 0.0, 0.0],
            [0.0, 0.0, wall_h],
        ),
        ("side_hi", [0.0, w, 0.0], [l, 0.0, 0.0], [0.0, 0.0, wall_h]),
    ];
    for (name, c, a, b) in walls {
        write_atomic(
            &dir.join(format!("{name}.stl")),
            rect_stl(name, c, a, b).as_bytes(),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::shear_box::Layout;

    fn record(class: &str) -> RunRecord {
        RunRecord {
            class: ModelClass::parse(class).unwrap(),
            layout: Layout {
                size: [0.03, 0.03, 0.045],
                diameters: vec![0.005, 0.004],
                d_min: 0.004,
                d_max: 0.005,
            },
            initial_positions: vec![[0.01, 0.01, 0.01], [0.02, 0.02, 0.02]],
            filled: vec![],
            dt: 1e-5,
            skin: 8e-4,
            fill_steps: 100,
            relax_steps: 10,
            flow_steps: 95,
            chunk: 10,
            trace: vec![],
            removal_height: -0.01,
            domain: ([-0.1; 3], [0.1; 3]),
            fill_seconds: 0.0,
            flow_seconds: 0.0,
            created: 2,
        }
    }

    fn params() -> ParamSet {
        ParamSet::from_pairs(&[
            ("E_p", 5e6),
            ("E_w", 5e6),
            ("nu_p", 0.3),
            ("e_pp", 0.5),
            ("e_pw", 0.5),
            ("mu_pp", 0.5),
            ("mu_pw", 0.3),
            ("mu_r_pp", 0.3),
            ("mu_r_pw", 0.3),
            ("rho_p", 2600.0),
            ("ced_pp", 3e4),
            ("ced_pw", 1e4),
        ])
    }

    fn script(class: &str) -> String {
        let dir = tempfile::tempdir().unwrap();
        write_deck(dir.path(), &params(), &record(class)).unwrap();
        std::fs::read_to_string(dir.path().join(INPUT)).unwrap()
    }

    #[test]
    fn the_default_class_writes_the_deck_it_always_wrote() {
        let s = script("hertz,mindlin,epsd2");
        let law = "model hertz tangential history rolling_friction epsd2";
        assert!(
            s.contains(&format!("pair_style gran {law}\npair_coeff")),
            "{s}"
        );
        assert!(s.contains(&format!(
            "wall/gran {law} mesh n_meshes 4 meshes floor back side_lo side_hi\n"
        )));
        assert!(s.contains("coefficientRollingFriction peratomtypepair 2 3e-1 3e-1 3e-1 3e-1\n\n"));
        assert!(
            !s.contains("cohesion") && !s.contains("tangential_reduce"),
            "{s}"
        );
    }

    #[test]
    fn sjkr_writes_cohesion_in_liggghts_order_with_the_caps_net_of_it() {
        let s = script("hertz,mindlin,epsd2,sjkr");
        let law = "model hertz tangential history cohesion sjkr rolling_friction epsd2";
        assert!(s.contains(&format!("pair_style gran {law}\n")), "{s}");
        assert!(s.contains(&format!(
            "wall/gran {law} mesh n_meshes 4 meshes floor back side_lo side_hi\n"
        )));
        assert!(!s.contains("tangential_reduce"), "{s}");
        assert!(s.contains(
            "fix m6 all property/global cohesionEnergyDensity peratomtypepair 2 3e4 1e4 1e4 1e4\n\n"
        ), "{s}");
    }

    #[test]
    fn classes_liggghts_lacks_are_refused_naming_the_effect() {
        for (class, effect) in [
            ("tsuji,mindlin", "tsuji"),
            ("kuwabara-kono,mindlin,epsd2", "kuwabara-kono"),
            ("power-damped,mindlin", "power-damped"),
            ("hertz,strict-coulomb,epsd2", "strict-coulomb"),
            ("hertz,linear-spring", "linear-spring"),
            ("hertz,mindlin,limit-force", "limit-force"),
        ] {
            let dir = tempfile::tempdir().unwrap();
            let e = write_deck(dir.path(), &params(), &record(class))
                .unwrap_err()
                .to_string();
            assert!(e.contains(effect) && e.contains("LIGGGHTS"), "{class}: {e}");
            assert!(!dir.path().join(INPUT).exists(), "{class}: no deck written");
        }
    }
}
