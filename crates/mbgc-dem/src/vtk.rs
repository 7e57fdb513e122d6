//! VTK snapshots (legacy ASCII polydata) of the particles, which ParaView opens directly: points
//! at the centres with radius, id, velocity, angular velocity and force. Glyph them with spheres
//! scaled by `radius` to see the packing.

use super::particles::Particles;
use std::fmt::Write as _;

/// The snapshot as the text of a legacy VTK file; the caller decides where it goes.
pub fn to_vtk(p: &Particles, title: &str) -> String {
    let n = p.len();
    let mut s = String::with_capacity(200 + n * 200);
    let _ = writeln!(s, "# vtk DataFile Version 3.0");
    let _ = writeln!(s, "{}", title.replace('\n', " "));
    let _ = writeln!(s, "ASCII\nDATASET POLYDATA\nPOINTS {n} double");
    for x in &p.x {
        let _ = writeln!(s, "{:e} {:e} {:e}", x[0], x[1], x[2]);
    }
    let _ = writeln!(s, "VERTICES {n} {}", 2 * n);
    for i in 0..n {
        let _ = writeln!(s, "1 {i}");
    }
    let _ = writeln!(
        s,
        "POINT_DATA {n}\nSCALARS radius double 1\nLOOKUP_TABLE default"
    );
    for r in &p.r {
        let _ = writeln!(s, "{r:e}");
    }
    let _ = writeln!(s, "SCALARS id int 1\nLOOKUP_TABLE default");
    for id in &p.id {
        let _ = writeln!(s, "{id}");
    }
    for (name, data) in [
        ("velocity", &p.v),
        ("angular_velocity", &p.w),
        ("force", &p.f),
    ] {
        let _ = writeln!(s, "VECTORS {name} double");
        for v in data {
            let _ = writeln!(s, "{:e} {:e} {:e}", v[0], v[1], v[2]);
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapshot_has_consistent_sections() {
        let mut p = Particles::new();
        p.add([0.0, 0.0, 0.1], 0.01, 2500.0, 0).unwrap();
        p.add([0.05, 0.0, 0.1], 0.02, 2500.0, 0).unwrap();
        p.v[1] = [1.5, 0.0, -2.0];
        let s = to_vtk(&p, "two");
        let lines: Vec<&str> = s.lines().collect();
        assert_eq!(lines[0], "# vtk DataFile Version 3.0");
        assert!(
            lines.contains(&"POINTS 2 double")
                && lines.contains(&"VERTICES 2 4")
                && lines.contains(&"POINT_DATA 2")
        );
        let v = lines
            .iter()
            .position(|l| *l == "VECTORS velocity double")
            .unwrap();
        let vals: Vec<f64> = lines[v + 2]
            .split(' ')
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(vals, vec![1.5, 0.0, -2.0]);
        let r = lines
            .iter()
            .position(|l| l.starts_with("SCALARS radius"))
            .unwrap();
        assert_eq!(lines[r + 3].parse::<f64>().unwrap(), 0.02);
    }
}
