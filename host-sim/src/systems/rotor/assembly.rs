//! Global matrices of the rotor: `M`, `C`, `G`, `K` assembled from the elements, and the
//! unbalance force.
//!
//! The matrices are dense `faer::Mat<f64>` of size `4 · nodes`. Dense storage is deliberate:
//! the paper rotor has 152 DOFs, the state matrix 304 states, and every analysis here (eigen
//! decomposition, matrix exponential, complex solve) is a dense operation anyway.

use super::config::RotorConfig;
use super::element::{Bearing, RigidBody, ShaftElement, NODE_DOFS};
use super::{dof, RotorError};
use faer::{c64, Mat};

/// The model's matrices: `M q̈ + (C + Ω G) q̇ + K q = f`.
#[derive(Debug, Clone, PartialEq)]
pub struct SystemMatrices {
    /// Mass, symmetric positive definite.
    pub m: Mat<f64>,
    /// Damping (shaft Rayleigh damping + bearings); not symmetric with cross-coupled bearings.
    pub c: Mat<f64>,
    /// Gyroscopic matrix (skew-symmetric), multiplied by the speed Ω.
    pub g: Mat<f64>,
    /// Stiffness; not symmetric with cross-coupled bearings.
    pub k: Mat<f64>,
}

impl SystemMatrices {
    /// Number of DOFs.
    pub fn n(&self) -> usize {
        self.m.nrows()
    }

    /// `C + Ω G`, the velocity matrix at speed `speed`.
    pub fn c_total(&self, speed: f64) -> Mat<f64> {
        Mat::from_fn(self.n(), self.n(), |i, j| self.c[(i, j)] + speed * self.g[(i, j)])
    }
}

/// The assembled finite-element model of a rotor.
///
/// ```
/// use edgekf_sim::systems::rotor::{RotorConfig, RotorModel};
/// let cfg = RotorConfig::from_toml_str(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/rotor_paper.toml"))).unwrap();
/// let model = RotorModel::from_config(&cfg).unwrap();
/// let s = model.assemble(87.96);
/// // Total mass seen by a rigid translation in x: shaft + two 2.65 kg disks.
/// let shaft = 7850.0 * std::f64::consts::PI / 4.0 * 0.017f64.powi(2) * 1.0;
/// let mass: f64 = (0..38).flat_map(|i| (0..38).map(move |j| (i, j))).map(|(i, j)| s.m[(4 * i, 4 * j)]).sum();
/// assert!((mass - (shaft + 5.3)).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct RotorModel {
    config: RotorConfig,
    z: Vec<f64>,
    matrices: SystemMatrices,
}

impl RotorModel {
    /// Builds the model of a configuration (validated first).
    pub fn from_config(config: &RotorConfig) -> Result<Self, RotorError> {
        config.validate()?;
        let n_nodes = config.n_nodes();
        let n = NODE_DOFS * n_nodes;
        let mut m = Mat::<f64>::zeros(n, n);
        let mut c = Mat::<f64>::zeros(n, n);
        let mut g = Mat::<f64>::zeros(n, n);
        let mut k = Mat::<f64>::zeros(n, n);

        let sh = &config.shaft;
        let shear_modulus = sh.young / (2.0 * (1.0 + sh.poisson));
        let mut z = vec![0.0];
        let mut node = 0;
        for s in &sh.sections {
            let l = s.length / s.elements as f64;
            let ratio = s.inner_diameter / s.diameter;
            let shear_factor = if sh.shear_deformation {
                sh.shear_factor.unwrap_or_else(|| super::element::cowper_shear_factor(ratio, sh.poisson))
            } else {
                0.0
            };
            let el = ShaftElement {
                length: l,
                outer_diameter: s.diameter,
                inner_diameter: s.inner_diameter,
                young: sh.young,
                shear_modulus,
                density: sh.density,
                shear_factor,
                rotary_inertia: sh.rotary_inertia,
                gyroscopic: sh.gyroscopic,
            };
            let e = el.matrices();
            for _ in 0..s.elements {
                let base = dof(node, 0);
                for i in 0..8 {
                    for j in 0..8 {
                        m[(base + i, base + j)] += e.m[i][j];
                        k[(base + i, base + j)] += e.k[i][j];
                        g[(base + i, base + j)] += e.g[i][j];
                        c[(base + i, base + j)] += sh.damping_alpha * e.m[i][j] + sh.damping_beta * e.k[i][j];
                    }
                }
                node += 1;
                let last = *z.last().unwrap_or(&0.0);
                z.push(last + l);
            }
        }

        let mut rigid = |node: usize, body: RigidBody| {
            let (mm, gg) = (body.mass_matrix(), body.gyroscopic_matrix());
            let base = dof(node, 0);
            for i in 0..4 {
                for j in 0..4 {
                    m[(base + i, base + j)] += mm[i][j];
                    g[(base + i, base + j)] += gg[i][j];
                }
            }
        };
        for d in &config.disks {
            let solid = RigidBody::solid_disk(d.mass, d.diameter, d.width);
            rigid(
                d.node,
                RigidBody {
                    mass: d.mass,
                    polar: d.ip.unwrap_or(solid.polar),
                    diametral: d.id.unwrap_or(solid.diametral),
                },
            );
        }
        for p in &config.masses {
            rigid(p.node, RigidBody { mass: p.mass, polar: p.ip, diametral: p.id });
        }
        for b in &config.bearings {
            let br = Bearing { k: [[b.kxx, b.kxy], [b.kyx, b.kyy]], c: [[b.cxx, b.cxy], [b.cyx, b.cyy]] };
            let base = dof(b.node, 0);
            for i in 0..2 {
                for j in 0..2 {
                    k[(base + i, base + j)] += br.k[i][j];
                    c[(base + i, base + j)] += br.c[i][j];
                }
            }
        }
        Ok(Self { config: config.clone(), z, matrices: SystemMatrices { m, c, g, k } })
    }

    /// The configuration the model was built from.
    pub fn config(&self) -> &RotorConfig {
        &self.config
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.z.len()
    }

    /// Number of DOFs (`4 · nodes`).
    pub fn n_dofs(&self) -> usize {
        NODE_DOFS * self.n_nodes()
    }

    /// Axial position of every node, m.
    pub fn node_positions(&self) -> &[f64] {
        &self.z
    }

    /// The speed-independent matrices (`C` without `Ω G`).
    pub fn matrices(&self) -> &SystemMatrices {
        &self.matrices
    }

    /// The matrices at a speed. Nothing in this model depends on speed except through `Ω G`,
    /// which [`SystemMatrices::c_total`] adds; the argument keeps the interface stable for
    /// speed-dependent bearings.
    pub fn assemble(&self, speed: f64) -> SystemMatrices {
        let _ = speed;
        self.matrices.clone()
    }

    /// The unbalance force as a complex amplitude per DOF: `f(t) = Re(F̂ e^{iΩt})`, N, with
    /// `F̂_x = U Ω² e^{iφ}` and `F̂_y = −i U Ω² e^{iφ}` (so `F_y = U Ω² sin(Ωt + φ)`).
    pub fn unbalance_phasor(&self, speed: f64) -> Vec<c64> {
        let mut f = vec![c64::new(0.0, 0.0); self.n_dofs()];
        for u in &self.config.unbalances {
            let amp = u.magnitude * speed * speed;
            let e = c64::from_polar(amp, u.phase_deg.to_radians());
            f[dof(u.node, 0)] += e;
            f[dof(u.node, 1)] += c64::new(0.0, -1.0) * e;
        }
        f
    }

    /// The total unbalance force on each unbalanced node at time `t` (constant speed),
    /// `(node, F_x, F_y)` in N, nodes in order of first appearance in the configuration.
    pub fn unbalance_forces(&self, speed: f64, t: f64) -> Vec<(usize, f64, f64)> {
        let mut out: Vec<(usize, f64, f64)> = Vec::new();
        for u in &self.config.unbalances {
            let amp = u.magnitude * speed * speed;
            let ph = speed * t + u.phase_deg.to_radians();
            let (fx, fy) = (amp * ph.cos(), amp * ph.sin());
            match out.iter_mut().find(|(n, _, _)| *n == u.node) {
                Some(e) => {
                    e.1 += fx;
                    e.2 += fy;
                }
                None => out.push((u.node, fx, fy)),
            }
        }
        out
    }
}
