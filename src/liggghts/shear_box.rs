//! The shear box (seed 004) as a LIGGGHTS 3.8 deck that replays a recorded mbgc run: the data
//! file with mbgc's initial particles, the five walls as STL meshes, and an input script with
//! mbgc's schedule, so that both codes start from the identical configuration and do the same
//! things at the same steps: fill, strike off at the rim, relax, remove the flap, and remove what
//! fell below the floor every chunk.
//!
//! `delete_atoms` must not compress the atom ids: LIGGGHTS keys the contact history by partner
//! id, and renumbering after every deletion scrambled the histories of the remaining contacts
//! (the replayed shear angle came out 2-3 degrees low until `compress no`).

use std::fmt::Write as _;
use std::path::Path;

use super::mesh::rect_stl;
use super::number::num;
use crate::dem::experiments::shear_box::RunRecord;
use crate::dem::experiments::ParamSet;
use crate::error::{write_atomic, Error, Result};

/// Name of the input script written by [`write_deck`].
pub const INPUT: &str = "in.shear_box";
/// Name of the log LIGGGHTS writes for it.
pub const LOG: &str = "log.shear_box";
/// Dumps the deck writes: after the fill and at the end.
pub const FILLED_DUMP: &str = "filled.dump";
pub const FINAL_DUMP: &str = "final.dump";

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
