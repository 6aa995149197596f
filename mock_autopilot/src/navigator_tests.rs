use super::*;
use crate::dynamics::Limits;

fn ctx<'a>(now: Duration, body: &'a Body, p: &'a NavParams) -> NavCtx<'a> {
    NavCtx {
        now,
        body,
        armed: true,
        p,
        home: Ned::zeros(),
        landed: false,
    }
}

fn run(nav: &mut Navigator, body: &mut Body, p: &NavParams, secs: f64, ev: &mut Vec<NavEvent>) {
    let lim = Limits::from_params(&ParamTable::default());
    let dt = 0.01;
    for k in 0..(secs / dt) as usize {
        let now = Duration::from_secs_f64(k as f64 * dt);
        let sp = nav.update(&ctx(now, body, p), ev);
        body.step(&sp, &lim, dt);
    }
}

#[test]
fn takeoff_mode_climbs_then_holds() {
    let p = NavParams::from_params(&ParamTable::default());
    let mut nav = Navigator::new();
    let mut body = Body::default();
    nav.set_mode(FlightMode::Takeoff, &body, 5.0);
    let mut ev = Vec::new();
    run(&mut nav, &mut body, &p, 20.0, &mut ev);
    assert!(ev.contains(&NavEvent::Mode(FlightMode::Loiter)));
    assert_eq!(nav.mode(), FlightMode::Loiter);
    assert!((body.pos_ned.z + 5.0).abs() < 0.9, "z {}", body.pos_ned.z);
}

#[test]
fn rtl_climbs_returns_and_lands_at_home() {
    let mut table = ParamTable::default();
    table.set("RTL_RETURN_ALT", crate::params::ParamValue::Float(15.0));
    let p = NavParams::from_params(&table);
    let mut nav = Navigator::new();
    let mut body = Body {
        pos_ned: Ned::new(30.0, -20.0, -5.0),
        ..Default::default()
    };
    nav.set_mode(FlightMode::Rtl, &body, 2.5);
    let mut ev = Vec::new();
    let mut min_z = 0.0f64;
    let lim = Limits::from_params(&table);
    for k in 0..12_000 {
        let now = Duration::from_millis(k * 10);
        let sp = nav.update(&ctx(now, &body, &p), &mut ev);
        body.step(&sp, &lim, 0.01);
        min_z = min_z.min(body.pos_ned.z);
    }
    assert!(min_z <= -14.0, "climbed to RTL_RETURN_ALT, min z {min_z}");
    assert!(
        body.pos_ned.xy().norm() < 1.0 && body.on_ground(),
        "at {:?}",
        body.pos_ned
    );
}

#[test]
fn jumps_are_bounded_and_speed_changes_apply() {
    let p = NavParams::from_params(&ParamTable::default());
    let mut nav = Navigator::new();
    nav.set_mission(vec![
        (MavCmd::MAV_CMD_DO_CHANGE_SPEED, NavKind::Speed { m_s: 2.0 }),
        (MavCmd::MAV_CMD_DO_JUMP, NavKind::Jump { to: 0, repeat: 2 }),
        (MavCmd::MAV_CMD_DO_JUMP, NavKind::Jump { to: 2, repeat: -1 }),
    ]);
    let body = Body::default();
    nav.set_mode(FlightMode::Mission, &body, 2.5);
    let mut ev = Vec::new();
    // An endless jump loop must not hang one update.
    for _ in 0..20 {
        let _ = nav.update(&ctx(Duration::ZERO, &body, &p), &mut ev);
    }
    assert!(ev.iter().filter(|e| matches!(e, NavEvent::Reached(0))).count() == 3);
    assert_eq!(nav.speed_m_s, Some(2.0));
}

#[test]
fn land_speed_slows_near_ground() {
    let p = NavParams::from_params(&ParamTable::default());
    assert_eq!(p.land_speed_at(20.0), p.down_m_s);
    assert_eq!(p.land_speed_at(2.0), p.land_speed_m_s);
    let mid = p.land_speed_at(7.5);
    assert!(mid > p.land_speed_m_s && mid < p.down_m_s);
}

#[test]
fn disarmed_is_idle_and_waypoints_list_next_two() {
    let p = NavParams::from_params(&ParamTable::default());
    let mut nav = Navigator::new();
    let wp = |n: f64| {
        (
            MavCmd::MAV_CMD_NAV_WAYPOINT,
            NavKind::Waypoint {
                target: Ned::new(n, 0.0, -5.0),
                hold_s: 0.0,
                acc_rad_m: None,
                forever: false,
            },
        )
    };
    nav.set_mission(vec![
        (MavCmd::MAV_CMD_SET_CAMERA_MODE, NavKind::Instant),
        wp(1.0),
        wp(2.0),
        wp(3.0),
    ]);
    let w = nav.waypoints();
    assert_eq!(w[0].map(|x| x.0.x), Some(1.0));
    assert_eq!(w[1].map(|x| x.0.x), Some(2.0));
    let body = Body::default();
    let mut c = ctx(Duration::ZERO, &body, &p);
    c.armed = false;
    assert_eq!(nav.update(&c, &mut Vec::new()), Setpoint::Idle);
}

#[test]
fn land_approach_is_reported_as_a_waypoint_at_the_approach_altitude() {
    let p = NavParams::from_params(&ParamTable::default());
    let mut nav = Navigator::new();
    nav.set_mission(vec![(
        MavCmd::MAV_CMD_NAV_LAND,
        NavKind::Land { xy: Some((0.0, 40.0)) },
    )]);
    // Before the item starts: the land point on the ground, as a land command.
    let w = nav.waypoints();
    assert_eq!(w[0], Some((Ned::new(0.0, 40.0, 0.0), MavCmd::MAV_CMD_NAV_LAND as u16)));
    nav.set_mode(FlightMode::Mission, &Body::default(), 0.0);
    let mut body = Body {
        pos_ned: Ned::new(0.0, 0.0, -10.0),
        ..Default::default()
    };
    let mut ev = Vec::new();
    run(&mut nav, &mut body, &p, 1.0, &mut ev);
    // Approaching: a plain waypoint above the land point at the altitude the approach began at (PX4's
    // "move to land"), however the vehicle's height wanders meanwhile.
    let (pos, cmd) = nav.waypoints()[0].unwrap();
    assert_eq!(cmd, u16::MAX, "PX4 leaves a plain position's command unset");
    assert!((pos - Ned::new(0.0, 40.0, -10.0)).norm() < 1e-9, "{pos:?}");
    body.pos_ned.z = -12.0;
    run(&mut nav, &mut body, &p, 0.5, &mut ev);
    assert!((nav.waypoints()[0].unwrap().0.z + 10.0).abs() < 1e-9);
    assert_eq!(nav.setpoint_command(), u16::MAX);
}
