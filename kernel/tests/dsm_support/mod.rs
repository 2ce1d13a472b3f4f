//! What the incremental-mesh test and the DSM bench share: a handset-like
//! concept of 20 primitives in 4 shape groups, kept as editable lists (the way
//! the server keeps a part's document) and built into a fresh [`Model`] after
//! every edit, and a small deterministic random generator.

#![allow(dead_code)]

pub mod mesh_checks;

use glam::DVec3;
use vsculpt_kernel::dsm::*;

/// xorshift64 (Marsaglia): seeded, reproducible, no dependency.
pub struct Rng(pub u64);

impl Rng {
    /// The next number in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A number in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }

    /// An index below n.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }

    /// A vector with components in [−s, s).
    pub fn vec(&mut self, s: f64) -> DVec3 {
        DVec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
}

/// One primitive of the editable model.
#[derive(Clone, Debug)]
pub enum Item {
    /// A geometric primitive.
    Geo(GeometricPrimitive),
    /// A density primitive.
    Den(DensityPrimitive),
}

/// One shape group: its primitives, its term (None: enters no term) and the
/// earlier groups it incorporates.
#[derive(Clone, Debug)]
pub struct GroupSpec {
    pub items: Vec<Item>,
    pub sign: Option<Sign>,
    pub incorporated: Vec<usize>,
}

/// The editable model.
#[derive(Clone, Debug)]
pub struct Spec {
    pub groups: Vec<GroupSpec>,
}

pub fn boxed(at: DVec3, half: DVec3, negative: bool) -> Item {
    let g = GeometricPrimitive::new(GeometricShape::Box { half }, Placement::at(at)).unwrap();
    Item::Geo(if negative { g.negated() } else { g })
}

pub fn cylinder(at: DVec3, radius: f64, half_height: f64, negative: bool) -> Item {
    let g = GeometricPrimitive::new(
        GeometricShape::Cylinder {
            radius,
            half_height,
        },
        Placement::at(at),
    )
    .unwrap();
    Item::Geo(if negative { g.negated() } else { g })
}

pub fn ball(at: DVec3, radius: f64, negative: bool) -> Item {
    let g = GeometricPrimitive::new(GeometricShape::Sphere { radius }, Placement::at(at)).unwrap();
    Item::Geo(if negative { g.negated() } else { g })
}

pub fn charge(at: DVec3, density: f64, reducing: f64) -> Item {
    Item::Den(DensityPrimitive::sphere(at, density, reducing).unwrap())
}

/// A handset concept (3.2 × 1.6 × 0.6 body) of 20 primitives:
/// * group 0 (add): the body box, two sphere-based end caps (D = 3, a = 3), a
///   density bump on the back, three side buttons, a screen recess and three
///   speaker slots (negative boxes), a camera boss (cylinder) with its lens
///   bore (negative cylinder), a home-key dimple (negative sphere), a volume
///   rocker, a negative charge denting the top;
/// * group 1 (subtract): a lanyard hole (cylinder) and a charging port (box);
/// * group 2 (no term): a grip ball, incorporated by group 3 (add), where it
///   fuses with a sphere-based charge into a thumb rest.
pub fn handset() -> Spec {
    let v = DVec3::new;
    let body = vec![
        boxed(v(0.0, 0.0, 0.0), v(1.6, 0.8, 0.3), false),
        charge(v(1.5, 0.0, 0.0), 3.0, 3.0),
        charge(v(-1.5, 0.0, 0.0), 3.0, 3.0),
        charge(v(0.2, 0.0, -0.6), 0.9, 4.0),
        boxed(v(-0.6, 0.82, 0.0), v(0.12, 0.04, 0.06), false),
        boxed(v(-0.25, 0.82, 0.0), v(0.12, 0.04, 0.06), false),
        boxed(v(0.1, 0.82, 0.0), v(0.08, 0.04, 0.06), false),
        boxed(v(0.0, 0.0, 0.3), v(1.1, 0.6, 0.05), true),
        boxed(v(-1.3, -0.15, 0.3), v(0.1, 0.02, 0.12), true),
        boxed(v(-1.3, 0.0, 0.3), v(0.1, 0.02, 0.12), true),
        boxed(v(-1.3, 0.15, 0.3), v(0.1, 0.02, 0.12), true),
        cylinder(v(1.0, 0.45, -0.3), 0.14, 0.06, false),
        ball(v(1.3, 0.0, 0.38), 0.12, true),
        boxed(v(0.8, -0.82, 0.0), v(0.2, 0.04, 0.05), false),
        cylinder(v(1.0, 0.45, -0.36), 0.08, 0.03, true),
        charge(v(-0.8, -0.4, 0.45), -0.4, 5.0),
    ];
    Spec {
        groups: vec![
            GroupSpec {
                items: body,
                sign: Some(Sign::Add),
                incorporated: vec![],
            },
            GroupSpec {
                items: vec![
                    cylinder(v(-1.4, 0.55, 0.0), 0.09, 0.5, false),
                    boxed(v(-1.62, 0.0, 0.0), v(0.08, 0.18, 0.06), false),
                ],
                sign: Some(Sign::Subtract),
                incorporated: vec![],
            },
            GroupSpec {
                items: vec![ball(v(0.6, -0.35, -0.3), 0.25, false)],
                sign: None,
                incorporated: vec![],
            },
            GroupSpec {
                items: vec![charge(v(0.6, -0.35, -0.45), 1.3, 6.0)],
                sign: Some(Sign::Add),
                incorporated: vec![2],
            },
        ],
    }
}

impl Spec {
    /// The kernel model (D_e = 1, default τ).
    pub fn model(&self) -> Model {
        let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
        for g in &self.groups {
            let mut group = Group {
                incorporated: g.incorporated.clone(),
                ..Group::default()
            };
            for it in &g.items {
                match it {
                    Item::Geo(p) => group.geometric.push(*p),
                    Item::Den(p) => group.density.push(p.clone()),
                }
            }
            let k = m.add_group(group).unwrap();
            if let Some(s) = g.sign {
                m.add_term(vec![k], s).unwrap();
            }
        }
        m
    }

    /// The number of primitives.
    pub fn len(&self) -> usize {
        self.groups.iter().map(|g| g.items.len()).sum()
    }

    /// Primitive `n` counted across groups: (group, index).
    pub fn locate(&self, mut n: usize) -> (usize, usize) {
        for (k, g) in self.groups.iter().enumerate() {
            if n < g.items.len() {
                return (k, n);
            }
            n -= g.items.len();
        }
        panic!("no primitive {n}");
    }

    /// Moves primitive `n` by `d`.
    pub fn translate(&mut self, n: usize, d: DVec3) {
        let (k, i) = self.locate(n);
        match &mut self.groups[k].items[i] {
            Item::Geo(p) => p.placement = p.placement.translated(d),
            Item::Den(p) => p.placement = p.placement.translated(d),
        }
    }
}

/// The DSM bench's shapes (a box rounded by 20 negative density primitives, 20
/// fused sphere-based charges) and the 20-primitive handset.
pub fn twenty_primitive_shapes() -> Vec<(&'static str, Model)> {
    let mut rounded = Model::new(1.0, DEFAULT_TAU).unwrap();
    rounded
        .add(
            vsculpt_kernel::dsm::shape_ops::rounded_box(
                DVec3::new(1.5, 1.0, 0.8),
                Placement::IDENTITY,
                0.3,
                1.0,
            )
            .unwrap(),
        )
        .unwrap();
    let mut blobby = Model::new(1.0, DEFAULT_TAU).unwrap();
    let density = (0..20)
        .map(|i| {
            let t = i as f64 / 20.0 * std::f64::consts::TAU;
            let c = DVec3::new(2.0 * t.cos(), 1.2 * (2.0 * t).sin(), 0.6 * (3.0 * t).cos());
            DensityPrimitive::sphere(c, 1.6, 1.5).unwrap()
        })
        .collect();
    blobby
        .add(Group {
            density,
            ..Default::default()
        })
        .unwrap();
    vec![
        ("rounded_box_20", rounded),
        ("blobby_20", blobby),
        ("handset", handset().model()),
    ]
}

/// One sphere-based density primitive (centre c, density d, reducing factor
/// a) in a model of presentation density `de`: the sphere r = ln(d/de)/a.
pub fn sphere_model(c: DVec3, d: f64, a: f64, de: f64) -> Model {
    let mut m = Model::new(de, DEFAULT_TAU).unwrap();
    m.add(Group {
        density: vec![DensityPrimitive::sphere(c, d, a).unwrap()],
        ..Default::default()
    })
    .unwrap();
    m
}

/// A ring of 16 sphere-based primitives (radius 3 about the z axis, D = 2,
/// a = 1.2) that fuses into a torus-like solid.
pub fn ring_of_charges() -> Model {
    let mut m = Model::new(1.0, DEFAULT_TAU).unwrap();
    let ring: Vec<DensityPrimitive> = (0..16)
        .map(|i| {
            let t = i as f64 / 16.0 * std::f64::consts::TAU;
            DensityPrimitive::sphere(DVec3::new(3.0 * t.cos(), 3.0 * t.sin(), 0.0), 2.0, 1.2)
                .unwrap()
        })
        .collect();
    m.add(Group {
        density: ring,
        ..Default::default()
    })
    .unwrap();
    m
}
