//! The shear box replayed in LIGGGHTS 3.8: mbgc writes the deck (data file with mbgc's initial
//! particles, the five walls as STL meshes, the input script with mbgc's schedule) so that both
//! codes start from the identical configuration and do the same things at the same steps:
//! fill, strike off at the rim, relax, remove the flap, and remove what fell below the floor
//! every chunk. Both settled states are then measured by the same code.
//!
//! `delete_atoms` must not compress the atom ids: LIGGGHTS keys the contact history by partner
//! id, and renumbering after every deletion scrambled the histories of the remaining contacts
//! (the replayed shear angle came out 2-3 degrees low until `compress no`).

use std::fmt::Write as _;
use std::path::Path;

use super::shear_box::{measure_flank, RunRecord};
use super::ParamSet;
use crate::dem::analysis::sphere_box_volume;
use crate::dem::liggghts::{find_binary, parse_dump_rows, run_deck};
use crate::dem::particles::Particles;
use crate::dem::vec3::V3;
use crate::error::{read_to_string, write_atomic, Error, Result};

pub const INPUT: &str = "in.shear_box";
pub const LOG: &str = "log.shear_box";

fn num(v: f64) -> String {
    format!("{v:e}")
}

/// ASCII STL of a rectangle (two triangles) from a corner and two edge vectors.
fn rect_stl(name: &str, corner: V3, a: V3, b: V3) -> String {
    let p = |u: f64, v: f64| {
        [
            corner[0] + u * a[0] + v * b[0],
            corner[1] + u * a[1] + v * b[1],
            corner[2] + u * a[2] + v * b[2],
        ]
    };
    let tri = |q: [V3; 3]| {
        let mut s = String::from("  facet normal 0 0 0\n    outer loop\n");
        for v in q {
            let _ = writeln!(s, "      vertex {} {} {}", num(v[0]), num(v[1]), num(v[2]));
        }
        s + "    endloop\n  endfacet\n"
    };
    format!(
        "solid {name}\n{}{}endsolid {name}\n",
        tri([p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0)]),
        tri([p(0.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)])
    )
}

/// Writes the data file, the wall meshes and the input script into `dir`.
pub fn write_deck(dir: &Path, p: &ParamSet, rec: &RunRecord) -> Result<()> {
    let get = |k: &str| {
        p.get(k)
            .ok_or_else(|| Error::invalid(format!("parameter {k}: missing")))
    };
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
    let (e_p, e_w, nu) = (get("E_p")?, get("E_w")?, get("nu_p")?);
    let (e_pp, e_pw, mu_pp, mu_pw, mr_pp, mr_pw) = (
        get("e_pp")?,
        get("e_pw")?,
        get("mu_pp")?,
        get("mu_pw")?,
        get("mu_r_pp")?,
        get("mu_r_pw")?,
    );
    let model = "model hertz tangential history rolling_friction epsd2";
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
    let _ = writeln!(
        s,
        "fix m1 all property/global youngsModulus peratomtype {} {}",
        num(e_p),
        num(e_w)
    );
    let _ = writeln!(
        s,
        "fix m2 all property/global poissonsRatio peratomtype {} {}",
        num(nu),
        num(nu)
    );
    let _ = writeln!(
        s,
        "fix m3 all property/global coefficientRestitution peratomtypepair 2 {} {} {} {}",
        num(e_pp),
        num(e_pw),
        num(e_pw),
        num(e_pw)
    );
    let _ = writeln!(
        s,
        "fix m4 all property/global coefficientFriction peratomtypepair 2 {} {} {} {}",
        num(mu_pp),
        num(mu_pw),
        num(mu_pw),
        num(mu_pw)
    );
    let _ = writeln!(
        s,
        "fix m5 all property/global coefficientRollingFriction peratomtypepair 2 {} {} {} {}\n",
        num(mr_pp),
        num(mr_pw),
        num(mr_pw),
        num(mr_pw)
    );
    let _ = writeln!(
        s,
        "pair_style gran {model}\npair_coeff * *\ntimestep {}",
        num(rec.dt)
    );
    let _ = writeln!(s, "fix gravity all gravity 9.81 vector 0.0 0.0 -1.0");
    for (name, ..) in &walls[..4] {
        let _ = writeln!(s, "fix {name} all mesh/surface file {name}.stl type 2");
    }
    let _ = writeln!(
        s,
        "fix box all wall/gran {model} mesh n_meshes 4 meshes floor back side_lo side_hi"
    );
    // LIGGGHTS takes one mesh wall fix only; the flap is a plane, which inside the box acts as
    // the flap rectangle does, and is gone before anything reaches beyond it.
    let _ = writeln!(
        s,
        "fix flapwall all wall/gran {model} primitive type 2 xplane {}",
        num(l)
    );
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
    let _ = writeln!(s, "write_dump all custom filled.dump id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"");
    let _ = writeln!(s, "unfix flapwall");
    let _ = writeln!(
        s,
        "region below block INF INF INF INF INF {} units box",
        num(rec.removal_height)
    );
    let _ = writeln!(s, "variable i loop {n_chunks}\nlabel flow\nrun {}\ndelete_atoms region below compress no\nnext i\njump SELF flow", rec.chunk);
    let _ = writeln!(s, "write_dump all custom final.dump id radius x y z modify format \"%d %.17g %.17g %.17g %.17g\"");
    write_atomic(&dir.join(INPUT), s.as_bytes())
}

fn particles_of(rows: &[(usize, f64, [f64; 3])]) -> Particles {
    let mut p = Particles::new();
    for (_, r, x) in rows {
        // Density is irrelevant to the geometric measures.
        let _ = p.add(*x, *r, 1.0, 0);
    }
    p
}

/// LIGGGHTS' shear angle, bulk density and flank R^2 for the replayed run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReplayResult {
    pub shear_angle: f64,
    pub bulk_density: f64,
    pub flank_r2: f64,
    pub particles_left: usize,
}

/// Replays a recorded mbgc run in LIGGGHTS (in `dir`) and measures it as mbgc does.
pub fn replay(dir: &Path, p: &ParamSet, rec: &RunRecord) -> Result<ReplayResult> {
    let binary = find_binary().ok_or_else(|| {
        Error::invalid("LIGGGHTS not found on PATH (Debian: apt-get install liggghts)")
    })?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for stale in ["filled.dump", "final.dump", LOG] {
        let f = dir.join(stale);
        if f.exists() {
            std::fs::remove_file(&f).map_err(|e| Error::io(&f, e))?;
        }
    }
    write_deck(dir, p, rec)?;
    run_deck(&binary, dir, INPUT, LOG)?;
    let [l, w, h] = rec.layout.size;
    let rho = p.get("rho_p").unwrap_or(f64::NAN);
    let read = |name: &str| -> Result<Vec<(usize, f64, [f64; 3])>> {
        let f = dir.join(name);
        parse_dump_rows(&f.display().to_string(), &read_to_string(&f)?)
    };
    let filled = read("filled.dump")?;
    let mass: f64 = filled
        .iter()
        .map(|(_, r, x)| rho * sphere_box_volume(*x, *r, [0.0; 3], [l, w, h]))
        .sum();
    let fin = particles_of(&read("final.dump")?);
    let flank = measure_flank(&fin, rec.layout.size, rec.layout.d_max);
    Ok(ReplayResult {
        shear_angle: (-flank.slope).atan().to_degrees(),
        bulk_density: mass / (l * w * h),
        flank_r2: flank.r2,
        particles_left: fin.len(),
    })
}
