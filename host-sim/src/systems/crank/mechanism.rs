//! The slider-crank's kinematics and equations of motion.
//!
//! # Formulation
//!
//! The paper models the mechanism in natural coordinates `q` (the Cartesian coordinates of the
//! joints) with constraints `Φ(q) = 0`, and integrates it with the R-matrix velocity
//! transformation `q̇ = R ż`, `Rᵀ M R z̈ = Rᵀ (Q − M Ṙ ż)`. We keep exactly that equation, with
//! one improvement: the position problem of a slider-crank has a closed-form solution, so the
//! dependent coordinates are computed from the independent ones instead of being iterated to
//! the constraint manifold.
//!
//! * Natural coordinates: ten numbers, the points `A` and `B` of the crank, `B` and `C` of the
//!   rod, and `C` of the slider. A clearance joint's two points differ by the eccentricity `e`;
//!   an ideal joint's coincide. With the centres of mass at mid-length the mass matrix of a bar
//!   in these coordinates is constant: `M_ii = m/4 + I_G/L²`, `M_ij = m/4 − I_G/L²`.
//! * Independent coordinates `z = [θ, e_A, e_B, e_C]` (see [`State`]): `A = e_A`,
//!   `B_crank = A + L₁ (cos θ, sin θ)`, `B_rod = B_crank − e_B`, the rod angle from the guide
//!   (`C_rod.y = −e_C.y`): `sin φ = −(e_C.y + B_rod.y) / L₂`, `cos φ > 0`, and
//!   `C_slider = C_rod + e_C`. `R = ∂q/∂z` and `Ṙ ż` follow analytically.
//!
//! Why this rather than natural coordinates with constraint stabilisation: the constraints hold
//! to rounding error by construction (no drift to correct, no Newton iteration, no projection,
//! no penalty or Lagrangian factor to tune), every step costs the same, and the state an
//! estimator sees is seven meaningful numbers. The map is regular everywhere because the rod is
//! longer than the crank plus the clearances (`|sin φ| < 1`), which the configuration checks.
//! [`Mechanism::constraint_residual`] evaluates the natural-coordinate constraints anyway, to
//! show it.
//!
//! Contact forces act along the line of centres, so their generalised force on `e_j` is simply
//! `−F n` (virtual work `F·δ(journal − bearing)`), and the joint reactions can be recovered
//! afterwards from the bodies' Newton–Euler equations ([`Mechanism::joint_forces`]), which
//! gives the `truth_contact_force_*` columns for ideal joints too and checks the dynamics.

use super::config::CrankConfig;
use super::contact::{ContactForce, ContactLaw};
use super::error::CrankError;
use super::state::{eccentricity_index, State, CRANK_ANGLE, DOF};
use super::Joint;

/// A small planar vector.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct V2 {
    x: f64,
    y: f64,
}

impl V2 {
    const ZERO: V2 = V2 { x: 0.0, y: 0.0 };
    fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
    fn dot(self, o: V2) -> f64 {
        self.x * o.x + self.y * o.y
    }
    fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    fn arr(self) -> [f64; 2] {
        [self.x, self.y]
    }
}

impl std::ops::Add for V2 {
    type Output = V2;
    fn add(self, o: V2) -> V2 {
        V2::new(self.x + o.x, self.y + o.y)
    }
}

impl std::ops::Sub for V2 {
    type Output = V2;
    fn sub(self, o: V2) -> V2 {
        V2::new(self.x - o.x, self.y - o.y)
    }
}

impl std::ops::Mul<f64> for V2 {
    type Output = V2;
    fn mul(self, s: f64) -> V2 {
        V2::new(self.x * s, self.y * s)
    }
}

/// Natural coordinates: crank A, crank B, rod B, rod C, slider C.
type Points = [V2; 5];
const CRANK_A: usize = 0;
const CRANK_B: usize = 1;
const ROD_B: usize = 2;
const ROD_C: usize = 3;
const SLIDER_C: usize = 4;

/// Positions that follow from `z`.
struct Kinematics {
    /// Crank direction `(cos θ, sin θ)` and its normal.
    u: V2,
    /// Rod direction `(cos φ, sin φ)` and its normal.
    w: V2,
    wn: V2,
    p: Points,
}

/// The positions of the joints' points, m (origin at the ground bearing's centre, x along the
/// guide towards the slider, y up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Crank end A (the journal at the ground joint).
    pub crank_a: [f64; 2],
    /// Crank end B.
    pub crank_b: [f64; 2],
    /// Rod end B.
    pub rod_b: [f64; 2],
    /// Rod end C.
    pub rod_c: [f64; 2],
    /// Slider point C (always on the guide, y = 0).
    pub slider_c: [f64; 2],
    /// Rod angle `φ` from the guide, rad.
    pub rod_angle: f64,
}

/// Accelerations and contact forces at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Dynamics {
    /// `z̈`: crank angular acceleration (rad/s²) and eccentricity accelerations (m/s²).
    pub zdd: [f64; DOF],
    /// Contact force at each joint A, B, C (zero for ideal joints and separated journals).
    pub contact: [ContactForce; 3],
    /// Power dissipated by contact damping, W.
    pub dissipation: f64,
}

impl Dynamics {
    /// Crank angular acceleration, rad/s²: what the sensor measures.
    pub fn crank_alpha(&self) -> f64 {
        self.zdd[CRANK_ANGLE]
    }
}

/// Mechanical energy, J.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Energy {
    /// Kinetic energy of the three bodies.
    pub kinetic: f64,
    /// Gravitational potential energy (zero at y = 0).
    pub gravity: f64,
    /// Elastic energy stored in the contacts.
    pub elastic: f64,
}

impl Energy {
    /// Kinetic + gravitational + elastic.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravity + self.elastic
    }
}

/// A slider-crank with a given set of clearance joints, ready to integrate.
///
/// ```
/// use edgekf_sim::systems::crank::{CrankConfig, Joint, Mechanism};
/// let ideal = Mechanism::new(&CrankConfig::default(), [None; 3]).unwrap();
/// assert_eq!(ideal.degrees_of_freedom(), 1);
/// let a = Mechanism::new(&CrankConfig::default(), [Some(0.25e-3), None, None]).unwrap();
/// assert_eq!(a.degrees_of_freedom(), 3);
/// assert_eq!(a.clearance(Joint::A), Some(0.25e-3));
/// // Released at 30° from rest, the crank starts to fall clockwise.
/// let d = ideal.dynamics(&ideal.release_state());
/// assert!(d.crank_alpha() < -10.0);
/// // Negative or absurd clearances are refused, not panicked on.
/// assert!(Mechanism::new(&CrankConfig::default(), [Some(-1e-3), None, None]).is_err());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Mechanism {
    config: CrankConfig,
    laws: [Option<ContactLaw>; 3],
    /// Indices into `z` that are integrated (θ, then the eccentricities of clearance joints).
    active: [usize; DOF],
    n_active: usize,
    l1: f64,
    l2: f64,
    /// Crank and rod mass-matrix blocks `(M_ii, M_ij)`.
    crank_m: (f64, f64),
    rod_m: (f64, f64),
    slider_m: f64,
    /// Weight on each natural-coordinate point, N (y components).
    weight: [f64; 5],
}

impl Mechanism {
    /// The mechanism of `config` with radial clearance `clearances[j]` (m) at joint A, B, C, or
    /// an ideal joint for `None`.
    pub fn new(config: &CrankConfig, clearances: [Option<f64>; 3]) -> Result<Self, CrankError> {
        config.validate()?;
        let mut laws = [None; 3];
        let mut total_clearance = 0.0;
        for joint in Joint::ALL {
            if let Some(c) = clearances[joint.index()] {
                let cc = &config.contact;
                let law = ContactLaw::new(
                    c,
                    cc.journal_radius_of(joint),
                    cc.young,
                    cc.poisson,
                    cc.restitution,
                    cc.min_impact_velocity,
                )
                .map_err(|e| CrankError::Config(format!("joint {joint}: {e}")))?;
                total_clearance += c;
                laws[joint.index()] = Some(law);
            }
        }
        let (l1, l2) = (config.crank.length, config.rod.length);
        // |sin φ| ≤ (L₁ + Σc + indentations) / L₂ must stay clear of 1; 5 % margin for the
        // indentations (micrometres) and for rounding.
        if l1 + 2.0 * total_clearance >= 0.95 * l2 {
            return Err(CrankError::Config(format!(
                "crank length {l1} m plus twice the clearances ({total_clearance} m) must stay below 95 % of the rod \
                 length {l2} m"
            )));
        }
        let mut active = [0; DOF];
        let mut n_active = 1;
        for joint in Joint::ALL {
            if laws[joint.index()].is_some() {
                let i = eccentricity_index(joint);
                active[n_active] = i;
                active[n_active + 1] = i + 1;
                n_active += 2;
            }
        }
        let bar = |m: f64, l: f64, i: f64| (m / 4.0 + i / (l * l), m / 4.0 - i / (l * l));
        let g = config.world.gravity;
        let (m1, m2, m3) = (config.crank.mass, config.rod.mass, config.slider.mass);
        Ok(Self {
            config: *config,
            laws,
            active,
            n_active,
            l1,
            l2,
            crank_m: bar(m1, l1, config.crank.inertia),
            rod_m: bar(m2, l2, config.rod.inertia),
            slider_m: m3,
            weight: [-0.5 * m1 * g, -0.5 * m1 * g, -0.5 * m2 * g, -0.5 * m2 * g, -m3 * g],
        })
    }

    /// The configuration it was built from.
    pub fn config(&self) -> &CrankConfig {
        &self.config
    }

    /// Radial clearance of `joint`, m (`None`: ideal joint).
    pub fn clearance(&self, joint: Joint) -> Option<f64> {
        self.laws[joint.index()].map(|l| l.clearance)
    }

    /// The three clearances as given to [`Mechanism::new`].
    pub fn clearances(&self) -> [Option<f64>; 3] {
        Joint::ALL.map(|j| self.clearance(j))
    }

    /// The contact law of `joint` (`None`: ideal joint).
    pub fn contact_law(&self, joint: Joint) -> Option<&ContactLaw> {
        self.laws[joint.index()].as_ref()
    }

    /// Number of degrees of freedom: 1 + 2 per clearance joint.
    pub fn degrees_of_freedom(&self) -> usize {
        self.n_active
    }

    /// Indices into [`State::z`] that are integrated.
    pub(crate) fn active(&self) -> &[usize] {
        &self.active[..self.n_active]
    }

    /// The state at release: crank at `release.crank_angle_deg`, at rest, every journal centred
    /// in its bearing, `t = 0`.
    pub fn release_state(&self) -> State {
        let mut z = [0.0; DOF];
        z[CRANK_ANGLE] = self.config.release.crank_angle_deg.to_radians();
        State { t: 0.0, z, zd: [0.0; DOF], impact_velocity: [None; 3], dissipated: 0.0 }
    }

    fn kinematics(&self, z: &[f64; DOF]) -> Kinematics {
        let (s, c) = z[CRANK_ANGLE].sin_cos();
        let u = V2::new(c, s);
        let ea = V2::new(z[1], z[2]);
        let eb = V2::new(z[3], z[4]);
        let ec = V2::new(z[5], z[6]);
        let a = ea;
        let b = a + u * self.l1;
        let br = b - eb;
        let sphi = -(ec.y + br.y) / self.l2;
        // NaN beyond |sin φ| = 1; the integrators stop on non-finite states.
        let cphi = (1.0 - sphi * sphi).sqrt();
        let w = V2::new(cphi, sphi);
        let cr = br + w * self.l2;
        Kinematics { u, w, wn: V2::new(-sphi, cphi), p: [a, b, br, cr, cr + ec] }
    }

    /// Point velocities for coordinate rates `zd` (linear in `zd`: with `z̈` in place of `ż`
    /// it gives `R z̈`), and the rod's angular velocity.
    fn velocities(&self, k: &Kinematics, zd: &[f64; DOF]) -> (Points, f64) {
        let un = V2::new(-k.u.y, k.u.x);
        let a = V2::new(zd[1], zd[2]);
        let b = a + un * (self.l1 * zd[CRANK_ANGLE]);
        let br = b - V2::new(zd[3], zd[4]);
        let phid = -(zd[6] + br.y) / (self.l2 * k.w.x);
        let cr = br + k.wn * (self.l2 * phid);
        (([a, b, br, cr, cr + V2::new(zd[5], zd[6])]), phid)
    }

    /// Point accelerations for `z̈ = 0`: `Ṙ ż`.
    fn bias_accelerations(&self, k: &Kinematics, theta_d: f64, phid: f64) -> Points {
        let b = k.u * (-self.l1 * theta_d * theta_d);
        let phidd = (self.l2 * k.w.y * phid * phid - b.y) / (self.l2 * k.w.x);
        let cr = b + k.wn * (self.l2 * phidd) - k.w * (self.l2 * phid * phid);
        [V2::ZERO, b, b, cr, cr]
    }

    fn mass_times(&self, v: &Points) -> Points {
        let (ci, cj) = self.crank_m;
        let (ri, rj) = self.rod_m;
        [
            v[CRANK_A] * ci + v[CRANK_B] * cj,
            v[CRANK_A] * cj + v[CRANK_B] * ci,
            v[ROD_B] * ri + v[ROD_C] * rj,
            v[ROD_B] * rj + v[ROD_C] * ri,
            v[SLIDER_C] * self.slider_m,
        ]
    }

    /// Indentation `δ = |e| − c` (m) and its rate (m/s) at `joint`; `None` for an ideal joint.
    pub fn penetration(&self, state: &State, joint: Joint) -> Option<(f64, f64)> {
        let law = self.laws[joint.index()].as_ref()?;
        Some(penetration_of(law, state.eccentricity(joint), state.eccentricity_rate(joint)))
    }

    /// Accelerations, contact forces and dissipated power in `state`.
    ///
    /// A contact force acts only while `state.impact_velocity` says a contact is in progress
    /// (see [`Mechanism::sync_contacts`]); this is what lets the adaptive integrator switch
    /// contact on and off exactly at located events.
    pub fn dynamics(&self, state: &State) -> Dynamics {
        self.eval(&state.z, &state.zd, &state.impact_velocity)
    }

    pub(crate) fn eval(&self, z: &[f64; DOF], zd: &[f64; DOF], memory: &[Option<f64>; 3]) -> Dynamics {
        let k = self.kinematics(z);
        let (_, phid) = self.velocities(&k, zd);
        let bias = self.bias_accelerations(&k, zd[CRANK_ANGLE], phid);
        let mb = self.mass_times(&bias);
        // Q − M Ṙ ż
        let mut f = [V2::ZERO; 5];
        for i in 0..5 {
            f[i] = V2::new(-mb[i].x, self.weight[i] - mb[i].y);
        }
        let n = self.n_active;
        let mut cols = [[V2::ZERO; 5]; DOF];
        let mut mcols = [[V2::ZERO; 5]; DOF];
        for (a, &i) in self.active().iter().enumerate() {
            let mut unit = [0.0; DOF];
            unit[i] = 1.0;
            cols[a] = self.velocities(&k, &unit).0;
            mcols[a] = self.mass_times(&cols[a]);
        }
        let mut mz = [[0.0; DOF]; DOF];
        let mut rhs = [0.0; DOF];
        for a in 0..n {
            rhs[a] = dot5(&cols[a], &f);
            for b in 0..=a {
                mz[a][b] = dot5(&cols[a], &mcols[b]);
            }
        }
        let mut out = Dynamics::default();
        let mut slot = 1;
        for joint in Joint::ALL {
            let Some(law) = &self.laws[joint.index()] else { continue };
            let i = eccentricity_index(joint);
            let e = V2::new(z[i], z[i + 1]);
            let (delta, rate) = penetration_of(law, e.arr(), [zd[i], zd[i + 1]]);
            let cf = law.force(delta, rate, memory[joint.index()]);
            if cf.total > 0.0 {
                let r = e.norm();
                rhs[slot] -= cf.total * e.x / r;
                rhs[slot + 1] -= cf.total * e.y / r;
            }
            out.dissipation += cf.dissipation(rate);
            out.contact[joint.index()] = cf;
            slot += 2;
        }
        if !cholesky_solve(&mut mz, &mut rhs, n) {
            out.zdd = [f64::NAN; DOF];
            return out;
        }
        for (a, &i) in self.active().iter().enumerate() {
            out.zdd[i] = rhs[a];
        }
        out
    }

    /// Starts or ends contacts from the geometry of `state`: a joint whose journal indents its
    /// bearing gets `Some(impact velocity)` if it had none (an impact; counted in `impacts`),
    /// one that is apart gets `None`. Ideal joints always get `None`.
    ///
    /// The fixed-step integrator calls this before every step; the adaptive one calls it only at
    /// located events and at the start of a run (so that any given state is consistent).
    pub fn sync_contacts(&self, state: &mut State, impacts: &mut [u64; 3]) {
        for joint in Joint::ALL {
            let j = joint.index();
            match (&self.laws[j], self.penetration(state, joint)) {
                (Some(law), Some((delta, rate))) if delta > 0.0 => {
                    if state.impact_velocity[j].is_none() {
                        state.impact_velocity[j] = Some(law.impact_velocity(rate));
                        impacts[j] += 1;
                    }
                }
                _ => state.impact_velocity[j] = None,
            }
        }
    }

    /// The joints' positions in `state`.
    pub fn pose(&self, state: &State) -> Pose {
        let k = self.kinematics(&state.z);
        Pose {
            crank_a: k.p[CRANK_A].arr(),
            crank_b: k.p[CRANK_B].arr(),
            rod_b: k.p[ROD_B].arr(),
            rod_c: k.p[ROD_C].arr(),
            slider_c: k.p[SLIDER_C].arr(),
            rod_angle: k.w.y.atan2(k.w.x),
        }
    }

    /// Slider position along the guide, m.
    pub fn slider_position(&self, state: &State) -> f64 {
        self.kinematics(&state.z).p[SLIDER_C].x
    }

    /// Largest violation of the natural-coordinate constraints in `state`, m: bar lengths,
    /// slider on the guide, and coincident points at ideal joints (A on the ground bearing's
    /// centre). Zero up to rounding by construction (see the module docs).
    pub fn constraint_residual(&self, state: &State) -> f64 {
        let p = self.kinematics(&state.z).p;
        let mut r: f64 = ((p[CRANK_B] - p[CRANK_A]).norm() - self.l1).abs();
        r = r.max(((p[ROD_C] - p[ROD_B]).norm() - self.l2).abs());
        r = r.max(p[SLIDER_C].y.abs());
        if self.laws[0].is_none() {
            r = r.max(p[CRANK_A].norm());
        }
        if self.laws[1].is_none() {
            r = r.max((p[CRANK_B] - p[ROD_B]).norm());
        }
        if self.laws[2].is_none() {
            r = r.max((p[SLIDER_C] - p[ROD_C]).norm());
        }
        r
    }

    /// Kinetic, gravitational and elastic energy in `state`.
    pub fn energy(&self, state: &State) -> Energy {
        let k = self.kinematics(&state.z);
        let (v, _) = self.velocities(&k, &state.zd);
        let mv = self.mass_times(&v);
        let kinetic = 0.5 * dot5(&v, &mv);
        let gravity = -(0..4).map(|i| self.weight[i] * k.p[i].y).sum::<f64>();
        let elastic = Joint::ALL
            .iter()
            .filter_map(|&j| self.laws[j.index()].as_ref().zip(self.penetration(state, j)))
            .map(|(law, (delta, _))| law.potential(delta))
            .sum();
        Energy { kinetic, gravity, elastic }
    }

    /// Force vectors transmitted by the joints, N, from the bodies' Newton–Euler equations with
    /// the accelerations `dynamics` (of `state`): on the crank at A from the ground, on the rod
    /// at B from the crank, on the rod at C from the slider.
    ///
    /// At a clearance joint this equals the contact force (a check of the dynamics); at an
    /// ideal joint it is the reaction a pin would carry.
    pub fn joint_forces(&self, state: &State, dynamics: &Dynamics) -> [[f64; 2]; 3] {
        let k = self.kinematics(&state.z);
        let (_, phid) = self.velocities(&k, &state.zd);
        let bias = self.bias_accelerations(&k, state.zd[CRANK_ANGLE], phid);
        let (rz, _) = self.velocities(&k, &dynamics.zdd);
        let acc: Points = std::array::from_fn(|i| rz[i] + bias[i]);
        let c = &self.config;
        let g = c.world.gravity;
        let (m1, m2) = (c.crank.mass, c.rod.mass);
        let a1 = (acc[CRANK_A] + acc[CRANK_B]) * 0.5;
        let a2 = (acc[ROD_B] + acc[ROD_C]) * 0.5;
        let phidd = (acc[ROD_C] - acc[ROD_B]).dot(k.wn) / self.l2;
        // Slider along the guide: only the rod pushes it.
        let fc_x = -self.slider_m * acc[SLIDER_C].x;
        // Rod: m₂ a₂ = F_B + F_C + m₂ g; I₂ φ̈ = (L₂/2) w × (F_C − F_B).
        let fb_x = m2 * a2.x - fc_x;
        let sum_y = m2 * (a2.y + g);
        let moment = 2.0 * c.rod.inertia * phidd / self.l2;
        let diff_y = (moment + k.w.y * (fc_x - fb_x)) / k.w.x;
        let fc = V2::new(fc_x, 0.5 * (sum_y + diff_y));
        let fb = V2::new(fb_x, 0.5 * (sum_y - diff_y));
        // Crank: m₁ a₁ = F_A − F_B + m₁ g.
        let fa = a1 * m1 + fb + V2::new(0.0, m1 * g);
        [fa.arr(), fb.arr(), fc.arr()]
    }

    /// A state of this mechanism carrying on from `state` of the mechanism `from` (same
    /// configuration, possibly different clearances), as an estimator needs when it changes a
    /// sigma point's clearance between windows.
    ///
    /// The paper's remark: a journal that was apart stays apart (its eccentricity is scaled with
    /// the clearance), and a journal in contact keeps its indentation `δ = |e| − c` (moved along
    /// the same direction), so a shrinking clearance never produces a sudden deep indentation and
    /// a force jump. The map is continuous at the contact boundary. A joint that becomes ideal
    /// is centred; a joint that gains clearance starts centred. Rates and contact memory are
    /// kept.
    ///
    /// ```
    /// use edgekf_sim::systems::crank::{CrankConfig, Joint, Mechanism};
    /// let cfg = CrankConfig::default();
    /// let old = Mechanism::new(&cfg, [Some(0.25e-3), None, None]).unwrap();
    /// let new = Mechanism::new(&cfg, [Some(0.1e-3), None, None]).unwrap();
    /// let mut s = old.release_state();
    /// s.set_eccentricity(Joint::A, [0.0, -0.251e-3], [0.0, -0.05]); // 1 µm into the bearing
    /// let t = new.transfer_state(&old, &s);
    /// let (delta, _) = new.penetration(&t, Joint::A).unwrap();
    /// assert!((delta - 1e-6).abs() < 1e-15);
    /// ```
    pub fn transfer_state(&self, from: &Mechanism, state: &State) -> State {
        let mut out = *state;
        for joint in Joint::ALL {
            let j = joint.index();
            match (from.clearance(joint), self.clearance(joint)) {
                (_, None) | (None, Some(_)) => {
                    out.set_eccentricity(joint, [0.0; 2], [0.0; 2]);
                    out.impact_velocity[j] = None;
                }
                (Some(c_old), Some(c_new)) => {
                    let [x, y] = state.eccentricity(joint);
                    let r = x.hypot(y);
                    let scale = if r <= c_old { c_new / c_old } else { (c_new + (r - c_old)) / r };
                    out.set_eccentricity(joint, [x * scale, y * scale], state.eccentricity_rate(joint));
                }
            }
        }
        out
    }
}

fn dot5(a: &Points, b: &Points) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

fn penetration_of(law: &ContactLaw, e: [f64; 2], ed: [f64; 2]) -> (f64, f64) {
    let r = e[0].hypot(e[1]);
    let rate = if r > 0.0 { (e[0] * ed[0] + e[1] * ed[1]) / r } else { 0.0 };
    (r - law.clearance, rate)
}

/// Solves `A x = b` for a symmetric positive definite `A` (lower triangle of the leading
/// `n × n` block used) in place; `b` becomes `x`. Returns false if `A` is not positive definite
/// (or not finite).
fn cholesky_solve(a: &mut [[f64; DOF]; DOF], b: &mut [f64; DOF], n: usize) -> bool {
    for j in 0..n {
        let d = a[j][j] - a[j][..j].iter().map(|v| v * v).sum::<f64>();
        if !(d.is_finite() && d > 0.0) {
            return false;
        }
        let d = d.sqrt();
        a[j][j] = d;
        for i in j + 1..n {
            let (upper, lower) = a.split_at_mut(i);
            let (row_j, row_i) = (&upper[j], &mut lower[0]);
            let s = row_i[j] - row_i[..j].iter().zip(&row_j[..j]).map(|(x, y)| x * y).sum::<f64>();
            row_i[j] = s / d;
        }
    }
    // L y = b, then Lᵀ x = y.
    for i in 0..n {
        let s = b[i] - a[i][..i].iter().zip(&b[..i]).map(|(x, y)| x * y).sum::<f64>();
        b[i] = s / a[i][i];
    }
    for i in (0..n).rev() {
        let s = b[i] - (i + 1..n).map(|k| a[k][i] * b[k]).sum::<f64>();
        b[i] = s / a[i][i];
    }
    true
}

#[cfg(test)]
mod tests;
