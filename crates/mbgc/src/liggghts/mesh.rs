//! Wall meshes as ASCII STL, the form LIGGGHTS' `mesh/surface` reads.

use std::fmt::Write as _;

use super::number::num;
use mbgc_dem::vec3::V3;

/// ASCII STL of a rectangle (two triangles) from a corner and two edge vectors.
pub fn rect_stl(name: &str, corner: V3, a: V3, b: V3) -> String {
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
