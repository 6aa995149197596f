use super::*;

const DT_S: f64 = 0.004;

fn params() -> LandParams {
    LandParams::from_params(&ParamTable::default())
}

fn flying() -> LandInputs {
    LandInputs {
        armed: true,
        vel_ned: Ned::new(0.0, 0.0, -1.0),
        acc_ned: Ned::zeros(),
        on_ground: false,
        vel_sp_ned: Some(Ned::new(0.0, 0.0, -1.0)),
    }
}

fn resting(vel_sp_ned: Option<Ned>) -> LandInputs {
    LandInputs {
        armed: true,
        vel_ned: Ned::zeros(),
        acc_ned: Ned::zeros(),
        on_ground: true,
        vel_sp_ned,
    }
}

/// A detector that has seen the vehicle climb away (not landed), then `secs` of `i`; returns the time
/// (since `i` began) at which it first said landed.
fn run(i: &LandInputs, secs: f64) -> (LandDetector, Option<f64>) {
    let p = params();
    let mut d = LandDetector::default();
    d.update(Duration::ZERO, DT_S, &flying(), &p);
    assert!(!d.landed() && !d.ground_contact(), "climbing is not landed");
    let mut landed_at = None;
    for k in 1..=(secs / DT_S) as u64 {
        let t = k as f64 * DT_S;
        d.update(Duration::from_secs_f64(t), DT_S, i, &p);
        if d.landed() && landed_at.is_none() {
            landed_at = Some(t);
        }
    }
    (d, landed_at)
}

#[test]
fn hysteresis_rises_late_and_falls_at_once() {
    let ms = Duration::from_millis;
    let mut h = Hysteresis::new(false);
    h.update(true, ms(0), ms(100));
    assert!(!h.get());
    h.update(true, ms(99), ms(100));
    assert!(!h.get());
    h.update(true, ms(100), ms(100));
    assert!(h.get());
    h.update(false, ms(101), ms(100));
    assert!(!h.get(), "true -> false has no delay");
    // An interrupted request starts over.
    h.update(true, ms(200), ms(100));
    h.update(false, ms(250), ms(100));
    h.update(true, ms(260), ms(100));
    h.update(true, ms(350), ms(100));
    assert!(!h.get());
    h.update(true, ms(360), ms(100));
    assert!(h.get());
}

#[test]
fn commanded_descent_on_the_ground_lands_after_the_three_stages() {
    // PX4's land setpoint on the ground: velocity z = MPC_LAND_SPEED (0.7 m/s down).
    let (d, at) = run(&resting(Some(Ned::new(0.0, 0.0, 0.7))), 5.0);
    let at = at.expect("landed");
    // The thrust winds down below 60 % of the range (0.35) in ~0.1 s, then three stages of 1/3 s.
    assert!(at > 1.0 && at < 1.3, "landed after {at} s");
    assert!(d.ground_contact() && d.maybe_landed());
    assert_eq!(d.thrust(), 0.0, "mc_pos_control cuts thrust on ground contact");
}

#[test]
fn idle_on_the_ground_lands() {
    let (_, at) = run(&resting(None), 3.0);
    let at = at.expect("landed");
    assert!((at - 1.0).abs() < 0.02, "idle is minimum thrust at once: {at} s");
}

#[test]
fn position_hold_at_the_ground_never_lands() {
    // A companion holding z = 0 with a position setpoint: no descent commanded, hover thrust.
    let (d, at) = run(&resting(Some(Ned::zeros())), 60.0);
    assert_eq!(at, None);
    assert!(!d.ground_contact());
    assert!((d.thrust() - 0.5).abs() < 1e-9, "hover thrust {}", d.thrust());
}

#[test]
fn slow_or_blocked_descents_do_not_count() {
    // Below 1.1 LNDMC_Z_VEL_MAX (0.275 m/s) the descent is not "commanded" (a position target 0.1 m below).
    let (_, at) = run(&resting(Some(Ned::new(0.0, 0.0, 0.15))), 30.0);
    assert_eq!(at, None);
    // Hovering 0.3 m up: not on the ground, hover thrust.
    let hover = LandInputs {
        on_ground: false,
        vel_ned: Ned::zeros(),
        vel_sp_ned: Some(Ned::zeros()),
        ..resting(None)
    };
    let (d, at) = run(&hover, 30.0);
    assert_eq!(at, None);
    assert!((d.thrust() - 0.5).abs() < 1e-9);
    // Sliding sideways faster than LNDMC_XY_VEL_MAX is movement, descent or not.
    let sliding = LandInputs {
        vel_ned: Ned::new(2.0, 0.0, 0.0),
        ..resting(Some(Ned::new(0.0, 0.0, 0.7)))
    };
    assert_eq!(run(&sliding, 10.0).1, None);
}

#[test]
fn disarmed_is_landed_and_takeoff_clears_it() {
    let p = params();
    let mut d = LandDetector::default();
    assert!(d.landed(), "boots landed");
    d.update(Duration::ZERO, DT_S, &flying(), &p);
    assert!(!d.landed());
    let disarmed = LandInputs {
        armed: false,
        ..flying()
    };
    d.update(Duration::from_millis(4), DT_S, &disarmed, &p);
    assert!(
        !d.landed(),
        "even disarmed, each stage takes its third of LNDMC_TRIG_TIME"
    );
    for k in 2..400 {
        d.update(Duration::from_millis(4 * k), DT_S, &disarmed, &p);
    }
    assert!(d.landed());
    assert_eq!(d.thrust(), 0.0);
}
