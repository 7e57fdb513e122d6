//! Analytic walls: infinite planes, finite rectangles, cylinders (inside surface) and flat plates
//! with a circular orifice. Each can translate with a constant velocity and be removed during a
//! run (the shear box's flap, the hopper's orifice shutter).

use super::vec3::*;
use crate::error::{Error, Result};

/// The geometry of a wall: analytic surfaces of zero thickness, so a particle's contact with
/// one is a sphere-surface overlap with R* = r and m* = m (the wall is infinitely massive).
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// Half-space boundary through `point`; particles live on the side `normal` points to.
    Plane {
        /// A point of the plane, m.
        point: V3,
        /// Unit normal pointing into the particles' side.
        normal: V3,
    },
    /// Rectangle centred at `center`, spanned by unit axes `u`, `v` with half extents; both faces
    /// and the edges repel particles.
    Rect {
        /// Centre, m.
        center: V3,
        /// First in-plane unit axis, orthogonal to `v`.
        u: V3,
        /// Second in-plane unit axis.
        v: V3,
        /// Half extent along `u`, m (> 0).
        half_u: f64,
        /// Half extent along `v`, m (> 0).
        half_v: f64,
    },
    /// Inside surface of a vertical cylinder (axis along z through `center` x, y), from `z_min` to
    /// `z_max`; particles live inside.
    Cylinder {
        /// A point of the axis (its z is not used), m.
        center: V3,
        /// Inner radius, m (> 0).
        radius: f64,
        /// Bottom of the mantle, m.
        z_min: f64,
        /// Top of the mantle, m (> `z_min`).
        z_max: f64,
    },
    /// Horizontal plate at height `center[2]`, from the orifice radius to `outer_radius` around
    /// the vertical axis through `center`; both faces and the orifice edge repel particles.
    OrificePlate {
        /// Centre of the orifice, m; its z is the plate's height.
        center: V3,
        /// Radius of the hole, m (>= 0; 0 for a plain disk).
        orifice_radius: f64,
        /// Outer radius of the plate, m (> `orifice_radius`).
        outer_radius: f64,
    },
}

/// A wall of a scene: a shape, a material and a constant translation velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct Wall {
    /// Label for messages and for callers that look a wall up (`xlo`, `flap`); not interpreted.
    pub name: String,
    /// Its geometry, moved by [`Wall::advance`].
    pub shape: Shape,
    /// Material index (see [`super::material::Materials`]).
    pub material: u16,
    /// Translation velocity, m/s.
    pub velocity: V3,
    /// Removed walls exert no force and lose their contact history.
    pub active: bool,
}

/// Closest point of the wall to a sphere centre: the unit normal from the wall to the centre and
/// the distance (negative if the centre lies behind a one-sided wall).
#[derive(Debug, Clone, Copy)]
pub struct WallGap {
    /// Unit normal from the closest wall point to the centre: the direction the contact force
    /// pushes the particle.
    pub normal: V3,
    /// Distance from the wall to the centre, m; the overlap is r - distance.
    pub distance: f64,
}

impl Wall {
    /// An active wall at rest; refuses a plane normal that is not a unit vector, rectangle axes
    /// that are not orthogonal unit vectors, and non-positive extents or radii. The material
    /// index is checked by [`crate::Simulation::new`].
    pub fn new(name: &str, shape: Shape, material: u16) -> Result<Wall> {
        let bad = |what: &str| Err(Error::invalid(format!("wall {name}: {what}")));
        match &shape {
            Shape::Plane { normal, .. } => {
                if (norm(*normal) - 1.0).abs() > 1e-9 {
                    return bad("plane normal must be a unit vector");
                }
            }
            Shape::Rect {
                u,
                v,
                half_u,
                half_v,
                ..
            } => {
                if (norm(*u) - 1.0).abs() > 1e-9
                    || (norm(*v) - 1.0).abs() > 1e-9
                    || dot(*u, *v).abs() > 1e-9
                {
                    return bad("rectangle axes must be orthogonal unit vectors");
                }
                if !(*half_u > 0.0 && *half_v > 0.0) {
                    return bad("rectangle half extents must be positive");
                }
            }
            Shape::Cylinder {
                radius,
                z_min,
                z_max,
                ..
            } => {
                if !(*radius > 0.0 && z_max > z_min) {
                    return bad("cylinder needs radius > 0 and z_max > z_min");
                }
            }
            Shape::OrificePlate {
                orifice_radius,
                outer_radius,
                ..
            } => {
                if !(*orifice_radius >= 0.0 && outer_radius > orifice_radius) {
                    return bad("orifice plate needs 0 <= orifice radius < outer radius");
                }
            }
        }
        Ok(Wall {
            name: name.to_string(),
            shape,
            material,
            velocity: [0.0; 3],
            active: true,
        })
    }

    /// A rectangle about `center` with unit axes `u`, `v` and half extents `half_u`, `half_v`.
    pub fn rect(
        name: &str,
        center: V3,
        (u, v): (V3, V3),
        (half_u, half_v): (f64, f64),
        material: u16,
    ) -> Result<Wall> {
        Wall::new(
            name,
            Shape::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            },
            material,
        )
    }

    /// The wall translating at `v`, m/s (a shear box's upper frame, a lid pressing down).
    pub fn with_velocity(mut self, v: V3) -> Self {
        self.velocity = v;
        self
    }

    /// Moves the wall by its velocity over `dt`.
    pub fn advance(&mut self, dt: f64) {
        if self.velocity == [0.0; 3] {
            return;
        }
        let d = scale(self.velocity, dt);
        match &mut self.shape {
            Shape::Plane { point, .. } => add_assign(point, d),
            Shape::Rect { center, .. }
            | Shape::Cylinder { center, .. }
            | Shape::OrificePlate { center, .. } => add_assign(center, d),
        }
        if let Shape::Cylinder { z_min, z_max, .. } = &mut self.shape {
            *z_min += d[2];
            *z_max += d[2];
        }
    }

    /// Gap between the wall and a point, or `None` when the point is farther than `reach` (m;
    /// the force loop passes the radius, the list build radius plus skin). A point exactly on a
    /// two-sided surface has no defined normal and also gives `None`.
    #[inline]
    pub fn gap(&self, x: V3, reach: f64) -> Option<WallGap> {
        match &self.shape {
            Shape::Plane { point, normal } => {
                let distance = dot(sub(x, *point), *normal);
                (distance < reach).then_some(WallGap {
                    normal: *normal,
                    distance,
                })
            }
            Shape::Rect {
                center,
                u,
                v,
                half_u,
                half_v,
            } => {
                let r = sub(x, *center);
                let a = dot(r, *u).clamp(-half_u, *half_u);
                let b = dot(r, *v).clamp(-half_v, *half_v);
                let q = add(*center, add(scale(*u, a), scale(*v, b)));
                closest(x, q, reach)
            }
            Shape::Cylinder {
                center,
                radius,
                z_min,
                z_max,
            } => {
                if x[2] < *z_min - reach || x[2] > *z_max + reach {
                    return None;
                }
                let (dx, dy) = (x[0] - center[0], x[1] - center[1]);
                let rho = (dx * dx + dy * dy).sqrt();
                if x[2] >= *z_min && x[2] <= *z_max {
                    let distance = radius - rho;
                    if distance >= reach || rho == 0.0 {
                        return None;
                    }
                    Some(WallGap {
                        normal: [-dx / rho, -dy / rho, 0.0],
                        distance,
                    })
                } else {
                    // Beyond an end: the rim circle is the closest part.
                    if rho == 0.0 {
                        return None;
                    }
                    let z = x[2].clamp(*z_min, *z_max);
                    let q = [
                        center[0] + dx / rho * radius,
                        center[1] + dy / rho * radius,
                        z,
                    ];
                    closest(x, q, reach)
                }
            }
            Shape::OrificePlate {
                center,
                orifice_radius,
                outer_radius,
            } => {
                let (dx, dy) = (x[0] - center[0], x[1] - center[1]);
                let rho = (dx * dx + dy * dy).sqrt();
                if (x[2] - center[2]).abs() >= reach {
                    return None;
                }
                let rc = rho.clamp(*orifice_radius, *outer_radius);
                let q = if rho > 0.0 {
                    [
                        center[0] + dx / rho * rc,
                        center[1] + dy / rho * rc,
                        center[2],
                    ]
                } else {
                    [center[0] + rc, center[1], center[2]]
                };
                closest(x, q, reach)
            }
        }
    }
}

#[inline]
fn closest(x: V3, q: V3, reach: f64) -> Option<WallGap> {
    let d = sub(x, q);
    let dist2 = norm2(d);
    if dist2 >= reach * reach || dist2 == 0.0 {
        return None;
    }
    let distance = dist2.sqrt();
    Some(WallGap {
        normal: scale(d, 1.0 / distance),
        distance,
    })
}

/// The six inward-facing planes of an axis-aligned box (named xlo, xhi, ylo, yhi, zlo, zhi).
pub fn box_planes(lo: V3, hi: V3, material: u16) -> Vec<Wall> {
    let mut walls = Vec::with_capacity(6);
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let mut n = [0.0; 3];
        n[k] = 1.0;
        walls.push(
            Wall::new(
                &format!("{axis}lo"),
                Shape::Plane {
                    point: lo,
                    normal: n,
                },
                material,
            )
            .expect("unit normal"),
        );
        n[k] = -1.0;
        walls.push(
            Wall::new(
                &format!("{axis}hi"),
                Shape::Plane {
                    point: hi,
                    normal: n,
                },
                material,
            )
            .expect("unit normal"),
        );
    }
    walls
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_point_from_wall_to_particle() {
        let p = Wall::new(
            "p",
            Shape::Plane {
                point: [0.0; 3],
                normal: [0.0, 0.0, 1.0],
            },
            0,
        )
        .unwrap();
        let g = p.gap([0.3, 0.1, 0.05], 0.1).unwrap();
        assert!((g.distance - 0.05).abs() < 1e-15 && g.normal == [0.0, 0.0, 1.0]);
        assert!(p.gap([0.0, 0.0, 0.2], 0.1).is_none());

        let c = Wall::new(
            "c",
            Shape::Cylinder {
                center: [0.0; 3],
                radius: 1.0,
                z_min: 0.0,
                z_max: 2.0,
            },
            0,
        )
        .unwrap();
        let g = c.gap([0.95, 0.0, 1.0], 0.1).unwrap();
        assert!((g.distance - 0.05).abs() < 1e-12 && (g.normal[0] + 1.0).abs() < 1e-12);

        let o = Wall::new(
            "o",
            Shape::OrificePlate {
                center: [0.0; 3],
                orifice_radius: 0.5,
                outer_radius: 2.0,
            },
            0,
        )
        .unwrap();
        // Above the solid part: straight up.
        let g = o.gap([1.0, 0.0, 0.05], 0.1).unwrap();
        assert!((g.distance - 0.05).abs() < 1e-12 && (g.normal[2] - 1.0).abs() < 1e-12);
        // Over the hole, near the edge: pushed away from the rim.
        let g = o.gap([0.45, 0.0, 0.0], 0.1).unwrap();
        assert!((g.distance - 0.05).abs() < 1e-12 && (g.normal[0] + 1.0).abs() < 1e-12);
        // Over the middle of the hole: free.
        assert!(o.gap([0.0, 0.0, 0.0], 0.1).is_none());

        let r = Wall::new(
            "r",
            Shape::Rect {
                center: [0.0; 3],
                u: [1.0, 0.0, 0.0],
                v: [0.0, 1.0, 0.0],
                half_u: 1.0,
                half_v: 1.0,
            },
            0,
        )
        .unwrap();
        let g = r.gap([1.05, 0.0, 0.0], 0.1).unwrap();
        assert!((g.distance - 0.05).abs() < 1e-12 && (g.normal[0] - 1.0).abs() < 1e-12);
    }
}
