use super::*;
use crate::systems::crank::CrankConfig;

/// Clearances at all three joints, and a state with every journal pressed 0.5–2 µm into its
/// bearing and moving, so that every term of the equations of motion is active.
fn loaded() -> (Mechanism, State) {
    let m = Mechanism::new(&CrankConfig::default(), [Some(0.25e-3), Some(0.1e-3), Some(0.05e-3)]).unwrap();
    let mut s = m.release_state();
    s.z[CRANK_ANGLE] = 2.1;
    s.zd[CRANK_ANGLE] = -7.3;
    let dirs = [(0.3_f64, 0.5e-6, 0.02), (2.0, 1.0e-6, 0.01), (-1.2, 2.0e-6, 0.03)];
    for (joint, (ang, depth, rate)) in Joint::ALL.into_iter().zip(dirs) {
        let c = m.clearance(joint).unwrap();
        let r = c + depth;
        let (sn, cs) = ang.sin_cos();
        s.set_eccentricity(joint, [r * cs, r * sn], [rate * cs - 0.04 * sn, rate * sn + 0.04 * cs]);
    }
    let mut impacts = [0; 3];
    m.sync_contacts(&mut s, &mut impacts);
    assert_eq!(impacts, [1, 1, 1]);
    (m, s)
}

fn points(m: &Mechanism, z: &[f64; DOF]) -> Points {
    m.kinematics(z).p
}

#[test]
fn velocity_transformation_matches_finite_differences() {
    let (m, s) = loaded();
    let k = m.kinematics(&s.z);
    let (v, _) = m.velocities(&k, &s.zd);
    let eps = 1e-7;
    let zp: [f64; DOF] = std::array::from_fn(|i| s.z[i] + eps * s.zd[i]);
    let zm: [f64; DOF] = std::array::from_fn(|i| s.z[i] - eps * s.zd[i]);
    let (pp, pm) = (points(&m, &zp), points(&m, &zm));
    for i in 0..5 {
        let fd = (pp[i] - pm[i]) * (0.5 / eps);
        assert!((fd - v[i]).norm() < 1e-7 * (1.0 + v[i].norm()), "point {i}: {fd:?} vs {:?}", v[i]);
    }
    // Ṙż: the derivative of the point velocities along the motion with ż held.
    let (vp, _) = m.velocities(&m.kinematics(&zp), &s.zd);
    let (vm, _) = m.velocities(&m.kinematics(&zm), &s.zd);
    let (_, phid) = m.velocities(&k, &s.zd);
    let bias = m.bias_accelerations(&k, s.zd[CRANK_ANGLE], phid);
    for i in 0..5 {
        let fd = (vp[i] - vm[i]) * (0.5 / eps);
        assert!((fd - bias[i]).norm() < 1e-5 * (1.0 + bias[i].norm()), "point {i}: {fd:?} vs {:?}", bias[i]);
    }
}

/// The equations of motion and the energy function agree: along the computed accelerations the
/// mechanical energy changes exactly by the power the contact damping dissipates. This checks
/// the mass matrix, the R-matrix terms, gravity and the contact forces together.
#[test]
fn energy_rate_equals_minus_dissipation() {
    let (m, s) = loaded();
    let d = m.dynamics(&s);
    assert!(d.dissipation > 0.0);
    let eps = 1e-9;
    let at = |sign: f64| {
        let mut x = s;
        for i in 0..DOF {
            x.z[i] += sign * eps * s.zd[i] + 0.5 * eps * eps * d.zdd[i];
            x.zd[i] += sign * eps * d.zdd[i];
        }
        m.energy(&x).total()
    };
    let rate = (at(1.0) - at(-1.0)) / (2.0 * eps);
    let scale = d.contact.iter().map(|c| c.total).sum::<f64>() * 0.05; // |F|·|δ̇| scale, W
    assert!((rate + d.dissipation).abs() < 1e-5 * scale, "dE/dt = {rate}, dissipation {}", d.dissipation);

    let ideal = Mechanism::new(&CrankConfig::default(), [None; 3]).unwrap();
    let mut s = ideal.release_state();
    s.zd[CRANK_ANGLE] = 12.0;
    let d = ideal.dynamics(&s);
    let at = |sign: f64| {
        let mut x = s;
        x.z[0] += sign * eps * s.zd[0];
        x.zd[0] += sign * eps * d.zdd[0];
        ideal.energy(&x).total()
    };
    assert!(((at(1.0) - at(-1.0)) / (2.0 * eps)).abs() < 1e-6);
}

#[test]
fn joint_forces_close_the_newton_euler_equations() {
    let (m, s) = loaded();
    let d = m.dynamics(&s);
    let f = m.joint_forces(&s, &d);
    // At clearance joints the recovered force is the contact force (on the crank journal at A,
    // on the rod's bearings at B and C).
    for joint in Joint::ALL {
        let [x, y] = s.eccentricity(joint);
        let r = x.hypot(y);
        let c = d.contact[joint.index()].total;
        let sign = if joint == Joint::A { -1.0 } else { 1.0 };
        let expect = [sign * c * x / r, sign * c * y / r];
        let got = f[joint.index()];
        assert!(
            (got[0] - expect[0]).abs() < 1e-9 * c && (got[1] - expect[1]).abs() < 1e-9 * c,
            "{joint}: {got:?} vs {expect:?}"
        );
    }
    // The crank's moment equation, not used to recover the forces, holds as well.
    let p = m.pose(&s);
    let g1 = [(p.crank_a[0] + p.crank_b[0]) / 2.0, (p.crank_a[1] + p.crank_b[1]) / 2.0];
    let cross = |r: [f64; 2], f: [f64; 2]| (r[0] - g1[0]) * f[1] - (r[1] - g1[1]) * f[0];
    let moment = cross(p.crank_a, f[0]) + cross(p.crank_b, [-f[1][0], -f[1][1]]);
    let i_alpha = CrankConfig::default().crank.inertia * d.crank_alpha();
    assert!((moment - i_alpha).abs() < 1e-9 * moment.abs().max(1e-3), "{moment} vs {i_alpha}");
}

#[test]
fn constraints_hold_to_rounding() {
    let (m, s) = loaded();
    assert!(m.constraint_residual(&s) < 1e-16, "{}", m.constraint_residual(&s));
    let p = m.pose(&s);
    assert!(p.slider_c[1].abs() < 1e-17, "{}", p.slider_c[1]);
}

#[test]
fn transfer_keeps_contact_indentation_and_free_ratio() {
    let cfg = CrankConfig::default();
    let (m, s) = loaded();
    let smaller = Mechanism::new(&cfg, [Some(0.1e-3), None, Some(0.2e-3)]).unwrap();
    let t = smaller.transfer_state(&m, &s);
    for joint in [Joint::A, Joint::C] {
        let before = m.penetration(&s, joint).unwrap().0;
        let after = smaller.penetration(&t, joint).unwrap().0;
        assert!((before - after).abs() < 1e-18, "{joint}: {before} → {after}");
    }
    assert_eq!(t.eccentricity(Joint::B), [0.0, 0.0]);
    assert_eq!(t.impact_velocity[1], None);
    assert_eq!(t.zd[CRANK_ANGLE], s.zd[CRANK_ANGLE]);
    // A journal that was apart stays apart, at the same fraction of the clearance.
    let mut free = m.release_state();
    free.set_eccentricity(Joint::A, [0.2e-3, 0.0], [0.0; 2]);
    let t = smaller.transfer_state(&m, &free);
    assert!((t.eccentricity(Joint::A)[0] - 0.08e-3).abs() < 1e-18);
}
