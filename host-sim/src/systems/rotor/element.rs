//! Element matrices: Timoshenko shaft element, rigid disk, point mass, linear bearing.
//!
//! Every matrix here uses the node DOF order of the crate (see [`crate::systems::rotor`]):
//! `[x, y, α, β]` per node, with `β = ∂x/∂z` (rotation about y) and `α = −∂y/∂z` (rotation about
//! x), so a shaft element's 8 DOFs are `[x₁, y₁, α₁, β₁, x₂, y₂, α₂, β₂]`.
//!
//! The shaft element is built from the textbook *planar* Timoshenko matrices (Przemieniecki's
//! stiffness, Archer/Friswell consistent translational and rotary mass, all with the shear
//! parameter `φ = 12EI/(κGAL²)`), written once for the xz-plane with DOFs `(x₁, β₁, x₂, β₂)`. The
//! yz-plane is the same beam seen through `(y, −α)`, so its matrices are `T P T` with
//! `T = diag(1, −1, 1, −1)`. The gyroscopic matrix follows from the kinetic-energy term
//! `−Ω ∫ ρIₚ α β̇ dz` with the same rotation interpolation, which gives
//! `G = [[0, R T], [−T R, 0]]` on `(xz, yz)` DOFs with `R = (Iₚ/I)·M_rotary`. Deriving all three
//! from one planar set (instead of typing 8×8 tables) is what keeps the sign conventions
//! consistent; the result is checked entry by entry against ROSS in `tests/rotor.rs`.

/// DOFs of one node: x, y, α (about x), β (about y).
pub const NODE_DOFS: usize = 4;

/// An 8×8 element matrix in the order `[x₁, y₁, α₁, β₁, x₂, y₂, α₂, β₂]`.
pub type Mat8 = [[f64; 8]; 8];

/// A 4×4 nodal matrix in the order `[x, y, α, β]`.
pub type Mat4 = [[f64; 4]; 4];

/// Positions of the xz-plane DOFs `(x₁, β₁, x₂, β₂)` in the element's 8-DOF order.
const XZ: [usize; 4] = [0, 3, 4, 7];
/// Positions of the yz-plane DOFs `(y₁, α₁, y₂, α₂)` in the element's 8-DOF order.
const YZ: [usize; 4] = [1, 2, 5, 6];
/// `(y, α) → (y, −α)`: the yz-plane expressed like the xz-plane.
const T: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// Cross-section and material of one shaft element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShaftElement {
    /// Length L, m.
    pub length: f64,
    /// Outer diameter, m.
    pub outer_diameter: f64,
    /// Inner diameter (0 for a solid shaft), m.
    pub inner_diameter: f64,
    /// Young's modulus E, Pa.
    pub young: f64,
    /// Shear modulus G, Pa.
    pub shear_modulus: f64,
    /// Density ρ, kg/m³.
    pub density: f64,
    /// Shear coefficient κ of the cross-section (0 turns shear deformation off: `φ = 0`).
    pub shear_factor: f64,
    /// Whether the rotary inertia of the cross-section is included.
    pub rotary_inertia: bool,
    /// Whether the gyroscopic matrix is included.
    pub gyroscopic: bool,
}

/// Mass, gyroscopic and stiffness matrices of one element (`G` multiplies the speed Ω).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementMatrices {
    /// Consistent mass (translational + rotary), kg / kg·m / kg·m².
    pub m: Mat8,
    /// Gyroscopic matrix (skew-symmetric), per rad/s of speed.
    pub g: Mat8,
    /// Stiffness, N/m / N / N·m.
    pub k: Mat8,
}

/// Cowper's shear coefficient of a hollow circular section with radius ratio `r = dᵢ/dₒ`:
/// `κ = 6(1+ν)(1+r²)² / ((7+6ν)(1+r²)² + (20+12ν)r²)` (6(1+ν)/(7+6ν) for a solid one; the ROSS
/// default, so both models use the same φ).
///
/// ```
/// use edgekf_sim::systems::rotor::element::cowper_shear_factor;
/// assert!((cowper_shear_factor(0.0, 0.29) - 6.0 * 1.29 / (7.0 + 6.0 * 0.29)).abs() < 1e-15);
/// ```
pub fn cowper_shear_factor(radius_ratio: f64, poisson: f64) -> f64 {
    let r2 = radius_ratio * radius_ratio;
    let r12 = (1.0 + r2) * (1.0 + r2);
    6.0 * r12 * (1.0 + poisson) / (r12 * (7.0 + 6.0 * poisson) + r2 * (20.0 + 12.0 * poisson))
}

impl ShaftElement {
    /// Cross-section area A, m².
    pub fn area(&self) -> f64 {
        std::f64::consts::PI / 4.0 * (self.outer_diameter.powi(2) - self.inner_diameter.powi(2))
    }

    /// Diametral second moment of area I, m⁴ (the polar one is 2I).
    pub fn second_moment(&self) -> f64 {
        std::f64::consts::PI / 64.0 * (self.outer_diameter.powi(4) - self.inner_diameter.powi(4))
    }

    /// Mass ρAL, kg.
    pub fn mass(&self) -> f64 {
        self.density * self.area() * self.length
    }

    /// Shear parameter `φ = 12EI/(κGAL²)` (0 without shear deformation).
    pub fn phi(&self) -> f64 {
        if self.shear_factor <= 0.0 {
            return 0.0;
        }
        12.0 * self.young * self.second_moment()
            / (self.shear_factor * self.shear_modulus * self.area() * self.length.powi(2))
    }

    /// The element's matrices in the 8-DOF order of the module.
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::element::{cowper_shear_factor, ShaftElement};
    /// let e = ShaftElement {
    ///     length: 0.1, outer_diameter: 0.02, inner_diameter: 0.0, young: 2.1e11,
    ///     shear_modulus: 2.1e11 / 2.6, density: 7850.0, shear_factor: cowper_shear_factor(0.0, 0.3),
    ///     rotary_inertia: true, gyroscopic: true,
    /// };
    /// let m = e.matrices();
    /// // Rigid translation in x: the consistent mass sums to the element's mass.
    /// let rigid = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
    /// let total: f64 = (0..8).map(|i| (0..8).map(|j| rigid[i] * m.m[i][j] * rigid[j]).sum::<f64>()).sum();
    /// assert!((total / e.mass() - 1.0).abs() < 1e-12);
    /// // ... and costs no strain energy.
    /// assert!((0..8).all(|i| (0..8).map(|j| m.k[i][j] * rigid[j]).sum::<f64>().abs() < 1e-6));
    /// ```
    pub fn matrices(&self) -> ElementMatrices {
        let l = self.length;
        let phi = self.phi();
        let ei = self.young * self.second_moment();
        let d = 1.0 + phi;

        // Planar stiffness (Przemieniecki), DOFs (x₁, β₁, x₂, β₂).
        let s = ei / (d * l.powi(3));
        let kp = [
            [12.0, 6.0 * l, -12.0, 6.0 * l],
            [6.0 * l, (4.0 + phi) * l * l, -6.0 * l, (2.0 - phi) * l * l],
            [-12.0, -6.0 * l, 12.0, -6.0 * l],
            [6.0 * l, (2.0 - phi) * l * l, -6.0 * l, (4.0 + phi) * l * l],
        ]
        .map(|row| row.map(|v| v * s));

        // Planar translational mass.
        let m1 = 13.0 / 35.0 + 7.0 * phi / 10.0 + phi * phi / 3.0;
        let m2 = 11.0 / 210.0 + 11.0 * phi / 120.0 + phi * phi / 24.0;
        let m3 = 9.0 / 70.0 + 3.0 * phi / 10.0 + phi * phi / 6.0;
        let m4 = 13.0 / 420.0 + 3.0 * phi / 40.0 + phi * phi / 24.0;
        let m5 = 1.0 / 105.0 + phi / 60.0 + phi * phi / 120.0;
        let m6 = 1.0 / 140.0 + phi / 60.0 + phi * phi / 120.0;
        let st = self.density * self.area() * l / (d * d);
        let mt = [
            [m1, m2 * l, m3, -m4 * l],
            [m2 * l, m5 * l * l, m4 * l, -m6 * l * l],
            [m3, m4 * l, m1, -m2 * l],
            [-m4 * l, -m6 * l * l, -m2 * l, m5 * l * l],
        ]
        .map(|row| row.map(|v| v * st));

        // Planar rotary inertia (per unit ρI; scaled below).
        let r7 = 6.0 / 5.0;
        let r8 = 1.0 / 10.0 - phi / 2.0;
        let r9 = 2.0 / 15.0 + phi / 6.0 + phi * phi / 3.0;
        let r10 = 1.0 / 30.0 + phi / 6.0 - phi * phi / 6.0;
        let sr = self.density * self.second_moment() / (d * d * l);
        let mr = [
            [r7, r8 * l, -r7, r8 * l],
            [r8 * l, r9 * l * l, -r8 * l, -r10 * l * l],
            [-r7, -r8 * l, r7, -r8 * l],
            [r8 * l, -r10 * l * l, -r8 * l, r9 * l * l],
        ]
        .map(|row| row.map(|v| v * sr));

        let mut mp = mt;
        if self.rotary_inertia {
            for i in 0..4 {
                for j in 0..4 {
                    mp[i][j] += mr[i][j];
                }
            }
        }

        let mut out = ElementMatrices { m: [[0.0; 8]; 8], g: [[0.0; 8]; 8], k: [[0.0; 8]; 8] };
        for i in 0..4 {
            for j in 0..4 {
                out.m[XZ[i]][XZ[j]] = mp[i][j];
                out.m[YZ[i]][YZ[j]] = T[i] * mp[i][j] * T[j];
                out.k[XZ[i]][XZ[j]] = kp[i][j];
                out.k[YZ[i]][YZ[j]] = T[i] * kp[i][j] * T[j];
                if self.gyroscopic {
                    // R = (Iₚ/I) M_rotary = 2 M_rotary for a circular section.
                    let rt = 2.0 * mr[i][j] * T[j];
                    out.g[XZ[i]][YZ[j]] = rt; // (R T) on xz rows, yz columns
                    out.g[YZ[j]][XZ[i]] = -rt; // −(T R) = −(R T)ᵀ
                }
            }
        }
        out
    }
}

/// A rigid disk (or any rigid body on one node): mass and inertias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBody {
    /// Mass, kg.
    pub mass: f64,
    /// Polar moment of inertia Iₚ about the shaft axis, kg·m².
    pub polar: f64,
    /// Diametral moment of inertia I_d about a diameter through the centre, kg·m².
    pub diametral: f64,
}

impl RigidBody {
    /// A solid disk of `mass`, outer `diameter` and axial `width`:
    /// `Iₚ = m D²/8`, `I_d = m (3 (D/2)² + w²)/12 = m D²/16 + m w²/12`.
    ///
    /// ```
    /// use edgekf_sim::systems::rotor::element::RigidBody;
    /// let d = RigidBody::solid_disk(2.65, 0.150, 0.020);
    /// assert!((d.polar - 2.65 * 0.15 * 0.15 / 8.0).abs() < 1e-15);
    /// assert!(d.diametral < d.polar); // a thin disk: I_d ≈ Iₚ/2
    /// ```
    pub fn solid_disk(mass: f64, diameter: f64, width: f64) -> Self {
        Self {
            mass,
            polar: mass * diameter * diameter / 8.0,
            diametral: mass * diameter * diameter / 16.0 + mass * width * width / 12.0,
        }
    }

    /// Mass matrix `diag(m, m, I_d, I_d)`.
    pub fn mass_matrix(&self) -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        m[0][0] = self.mass;
        m[1][1] = self.mass;
        m[2][2] = self.diametral;
        m[3][3] = self.diametral;
        m
    }

    /// Gyroscopic matrix: `I_d α̈ + Ω Iₚ β̇ = M_α`, `I_d β̈ − Ω Iₚ α̇ = M_β`, so `G[α][β] = Iₚ`,
    /// `G[β][α] = −Iₚ`.
    pub fn gyroscopic_matrix(&self) -> Mat4 {
        let mut g = [[0.0; 4]; 4];
        g[2][3] = self.polar;
        g[3][2] = -self.polar;
        g
    }
}

/// A linear bearing: the force on the shaft is `−K [x, y]ᵀ − C [ẋ, ẏ]ᵀ`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Bearing {
    /// Stiffness `[[kxx, kxy], [kyx, kyy]]`, N/m.
    pub k: [[f64; 2]; 2],
    /// Damping `[[cxx, cxy], [cyx, cyy]]`, N·s/m.
    pub c: [[f64; 2]; 2],
}

#[cfg(test)]
mod tests {
    use super::*;

    fn element(phi_on: bool) -> ShaftElement {
        ShaftElement {
            length: 0.05,
            outer_diameter: 0.04,
            inner_diameter: 0.01,
            young: 2.0e11,
            shear_modulus: 2.0e11 / 2.6,
            density: 7800.0,
            shear_factor: if phi_on { cowper_shear_factor(0.25, 0.3) } else { 0.0 },
            rotary_inertia: true,
            gyroscopic: true,
        }
    }

    #[test]
    fn matrices_are_symmetric_and_gyroscopic_is_skew() {
        for on in [false, true] {
            let m = element(on).matrices();
            for i in 0..8 {
                for j in 0..8 {
                    let tol = 1e-12 * (m.k[i][i].abs() + m.k[j][j].abs());
                    assert!((m.k[i][j] - m.k[j][i]).abs() <= tol, "K[{i}][{j}]");
                    assert!((m.m[i][j] - m.m[j][i]).abs() <= 1e-12 * (m.m[i][i] + m.m[j][j]), "M[{i}][{j}]");
                    assert_eq!(m.g[i][j], -m.g[j][i], "G[{i}][{j}]");
                }
            }
        }
    }

    #[test]
    fn rigid_rotation_is_strain_free() {
        // Rigid rotation about y by a small angle b: x = b z, β = b at both ends.
        let e = element(true);
        let m = e.matrices();
        let b = 1e-3;
        let q = [0.0, 0.0, 0.0, b, b * e.length, 0.0, 0.0, b];
        for row in &m.k {
            let f: f64 = row.iter().zip(&q).map(|(k, q)| k * q).sum();
            assert!(f.abs() < 1e-9 * m.k[0][0], "{f}");
        }
        // And about x: y = −a z, α = a.
        let q = [0.0, 0.0, b, 0.0, 0.0, -b * e.length, b, 0.0];
        for row in &m.k {
            let f: f64 = row.iter().zip(&q).map(|(k, q)| k * q).sum();
            assert!(f.abs() < 1e-9 * m.k[0][0], "{f}");
        }
    }

    #[test]
    fn rotary_mass_of_a_rigid_rotation_is_the_diametral_inertia() {
        // Rigid rotation about a diameter through node 1 with unit rate: the kinetic energy of
        // translation is ρA ∫ z² dz / 2 and of rotation ρI L / 2, with or without shear.
        for on in [false, true] {
            let e = element(on);
            let m = e.matrices();
            let l = e.length;
            let q = [0.0, 0.0, 0.0, 1.0, l, 0.0, 0.0, 1.0];
            let t2: f64 = (0..8).map(|i| (0..8).map(|j| q[i] * m.m[i][j] * q[j]).sum::<f64>()).sum();
            let expect = e.density * e.area() * l.powi(3) / 3.0 + e.density * e.second_moment() * l;
            assert!((t2 / expect - 1.0).abs() < 1e-12, "{t2} vs {expect}");
        }
    }
}
