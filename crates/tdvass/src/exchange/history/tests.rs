use super::*;

fn sine(t: f64) -> (f64, f64, f64) {
    (t, (3.0 * t).sin(), 3.0 * (3.0 * t).cos())
}

fn times(h: &DelayHistory) -> Vec<f64> {
    h.points().map(|p| p.time).collect()
}

#[test]
fn before_the_start_the_initial_position_is_held() {
    let h = DelayHistory::new(1.0, 0.5, 2.0, 0.1);
    assert_eq!(h.delayed((1.05, 9.0, 9.0)), Delayed::held(0.5));
}

#[test]
fn a_delay_shorter_than_the_step_interpolates_towards_the_current_state() {
    let tau = 2e-4;
    let mut h = DelayHistory::new(0.0, 0.0, 3.0, tau);
    let mut t = 0.0;
    while t < 0.5 {
        t += 1e-3;
        h.accept(sine(t), true);
    }
    let now = sine(t + 1e-3);
    let exact = (3.0 * (now.0 - tau)).sin();
    let error = (h.delayed(now).value - exact).abs();
    assert!(error < 1e-10, "{error}");
    // Extrapolating from the last point alone would be far off.
    assert!((h.points.back().unwrap().position - exact).abs() > 1e-4);
}

#[test]
fn the_partials_are_those_of_the_current_state() {
    let tau = 2e-4;
    let mut h = DelayHistory::new(0.0, 0.0, 3.0, tau);
    // An event: the master does not complete its steps.
    h.accept(sine(1e-3), false);
    let (t, x, v) = sine(1.7e-3);
    let d = h.delayed((t, x, v));
    let step = 1e-6;
    let by_x =
        (h.delayed((t, x + step, v)).value - h.delayed((t, x - step, v)).value) / (2.0 * step);
    let by_v =
        (h.delayed((t, x, v + step)).value - h.delayed((t, x, v - step)).value) / (2.0 * step);
    assert!((d.by_position - by_x).abs() < 1e-9, "{d:?} {by_x}");
    assert!((d.by_velocity - by_v).abs() < 1e-12, "{d:?} {by_v}");
    assert!(d.by_position > 0.0 && d.by_velocity < 0.0);
    // From the history alone: no dependence on the current state.
    let d = h.delayed(sine(1e-3 + tau + 1e-4));
    assert!(d.by_position > 0.0);
    let d = h.delayed(sine(1e-3 + tau));
    assert_eq!((d.by_position, d.by_velocity), (0.0, 0.0));
}

#[test]
fn hermite_interpolation_is_fourth_order() {
    let tau = 0.011;
    let error = |step: f64| {
        let mut h = DelayHistory::new(0.0, 0.0, 3.0, tau);
        let mut t = 0.0;
        while t < 0.3 {
            t += step;
            h.record(sine(t));
        }
        let now = sine(t + 0.37 * step);
        (h.delayed(now).value - (3.0 * (now.0 - tau)).sin()).abs()
    };
    let (coarse, fine) = (error(4e-3), error(2e-3));
    assert!(coarse / fine > 12.0, "{coarse} {fine}");
}

#[test]
fn time_moving_back_drops_the_trial_points_after_it_and_keeps_the_accepted_ones() {
    let mut h = DelayHistory::new(0.0, 0.0, 0.0, 1.0);
    h.accept((0.1, 1.0, 0.0), true);
    h.record((0.2, 2.0, 0.0));
    h.record((0.3, 3.0, 0.0));
    h.record((0.15, 1.5, 0.0));
    assert_eq!(times(&h), [0.0, 0.1, 0.15]);
    // The same instant again replaces a trial point.
    h.record((0.15, 7.0, 0.0));
    assert_eq!(h.points().last().unwrap().position, 7.0);
    assert_eq!(h.accepted_time(), 0.1);
    // An evaluation at an accepted instant leaves it.
    h.record((0.1, 5.0, 0.0));
    assert_eq!(times(&h), [0.0, 0.1]);
    assert_eq!(h.points().last().unwrap().position, 1.0);
}

#[test]
fn a_completed_step_drops_its_stages() {
    let mut h = DelayHistory::new(0.0, 0.0, 0.0, 1.0);
    // RK4: stages at t + h/2 (twice) and t + h, then the step's end.
    h.record((0.0, 0.0, 0.0));
    h.record((0.5, 9.0, 0.0));
    h.record((0.5, 8.0, 0.0));
    h.record((1.0, 7.0, 0.0));
    h.accept((1.0, 1.0, 0.0), true);
    assert_eq!(times(&h), [0.0, 1.0]);
    assert_eq!(h.points().last().unwrap().position, 1.0);
    assert!(h.habits().0);
    // While it does, a stage interpolates past the stages before it.
    h.record((1.5, 100.0, 0.0));
    let through_accepted = h.delayed((2.2, 2.0, 0.0)).value;
    let fresh = {
        let mut g = DelayHistory::new(0.0, 0.0, 0.0, 1.0);
        g.accept((1.0, 1.0, 0.0), true);
        g.delayed((2.2, 2.0, 0.0)).value
    };
    assert_eq!(through_accepted, fresh);
}

#[test]
fn a_completion_after_many_steps_keeps_them() {
    let mut h = DelayHistory::new(0.0, 0.0, 0.0, 1.0);
    for i in 1..=STAGE_POINTS + 1 {
        h.record(sine(i as f64 * 0.01));
    }
    h.accept(sine(0.2), true);
    assert_eq!(h.points().len(), STAGE_POINTS + 3);
    assert!(h.points().all(|p| p.accepted));
    assert!(!h.habits().0);
}

#[test]
fn a_completion_at_an_interpolated_point_keeps_the_points_on_both_sides() {
    let mut h = DelayHistory::new(0.0, 0.0, 0.0, 1.0);
    h.record((0.1, 1.0, 0.0));
    h.record((0.3, 3.0, 0.0));
    // The solver stepped to 0.3 and returns to the output point 0.2.
    h.accept((0.2, 2.0, 0.0), true);
    assert_eq!(times(&h), [0.0, 0.1, 0.2, 0.3]);
    let accepted: Vec<bool> = h.points().map(|p| p.accepted).collect();
    assert_eq!(accepted, [true, true, true, false]);
    assert_eq!(h.accepted_time(), 0.2);
    assert!(!h.habits().0);
    // Going on from 0.3 keeps them; going back to 0.25 drops 0.3.
    h.record((0.25, 2.5, 0.0));
    assert_eq!(times(&h), [0.0, 0.1, 0.2, 0.25]);
}

#[test]
fn trimming_keeps_what_times_from_the_floor_need() {
    let mut h = DelayHistory::new(0.0, 0.0, 3.0, 0.01);
    for i in 1..100_000 {
        h.accept(sine(i as f64 * 1e-4), true);
        h.trim(i as f64 * 1e-4);
    }
    // tau / step + the one before.
    assert!(h.points.len() <= 102, "{}", h.points.len());
    let earliest = h.earliest_time();
    assert!(earliest <= h.accepted_time(), "{earliest}");
    let s = h.accepted_time() - 0.01;
    let d = h.delayed(sine(h.accepted_time())).value;
    assert!((d - (3.0 * s).sin()).abs() < 1e-12);
}

#[test]
fn at_most_the_bound_of_points_is_kept() {
    let mut h = DelayHistory::new(0.0, 0.0, 3.0, 0.01);
    for i in 1..=MAX_HISTORY_POINTS + 10 {
        h.record(sine(i as f64 * 1e-6));
    }
    assert_eq!(h.points.len(), MAX_HISTORY_POINTS);
    assert!(h.points.front().unwrap().accepted);
    assert_eq!(h.earliest_time(), 11e-6 + 0.01);
}

#[test]
fn restored_points_are_checked() {
    let p = |time, accepted| HistoryPoint {
        accepted,
        ..HistoryPoint::trial((time, 0.0, 0.0))
    };
    let from = |points: Vec<HistoryPoint>| {
        DelayHistory::from_points(0.0, 0.0, 0.1, points, (false, false))
    };
    assert!(from(vec![p(0.0, true), p(0.1, false)]).is_ok());
    assert!(from(vec![]).is_err());
    assert!(from(vec![p(0.0, false)]).is_err());
    assert!(from(vec![p(0.0, true), p(0.0, false)]).is_err());
    assert!(from(vec![p(-1.0, true)]).is_err());
    assert!(from(vec![p(0.0, true), p(0.1, false), p(0.2, true)]).is_err());
    let stage = HistoryPoint {
        superseded_by: 0.05,
        ..p(0.1, false)
    };
    assert!(from(vec![p(0.0, true), stage]).is_err());
}

#[test]
fn a_re_evaluated_step_end_supersedes_the_stages_for_later_times_only() {
    let mut h = DelayHistory::new(0.0, 0.0, 0.0, 0.3);
    // RK4 that never completes: k1, k2, k3, k4, then the next k1.
    h.record((0.0, 0.0, 0.0));
    h.record((0.5, 9.0, 0.0));
    h.record((0.5, 8.0, 0.0));
    h.record((1.0, 7.0, 0.0));
    // At the step end, before and after its re-evaluation, the stage is
    // used alike: every evaluation at one instant sees one function.
    let before = h.delayed((1.0, 1.0, 0.0));
    h.record((1.0, 1.0, 0.0));
    assert_eq!(h.delayed((1.0, 1.0, 0.0)), before);
    assert_eq!(h.points().map(|p| p.superseded_by).nth(1), Some(1.0));
    assert!(h.points().last().unwrap().anchor);
    // Later, the delayed value interpolates between the step's ends.
    let later = h.delayed((1.2, 2.0, 0.0)).value;
    let without = {
        let mut g = DelayHistory::new(0.0, 0.0, 0.0, 0.3);
        g.record((1.0, 1.0, 0.0));
        g.delayed((1.2, 2.0, 0.0)).value
    };
    assert_eq!(later, without);
    // Back before the step end: the stage is a point again.
    h.record((0.7, 3.0, 0.0));
    assert_eq!(times(&h), [0.0, 0.5, 0.7]);
    assert!(h.points().all(|p| p.superseded_by == f64::INFINITY));
}

#[test]
fn back_to_the_step_end_keeps_it_the_anchor() {
    let mut h = DelayHistory::new(0.0, 0.0, 0.0, 0.3);
    for (t, x) in [
        (0.5, 9.0),
        (0.5, 8.0),
        (1.0, 7.0),
        (1.0, 1.0),
        (1.5, 5.0),
        (2.0, 6.0),
    ] {
        h.record((t, x, 0.0));
    }
    h.record((1.0, 1.0, 0.0));
    assert_eq!(times(&h), [0.0, 0.5, 1.0]);
    assert!(h.points().last().unwrap().anchor);
    assert_eq!(h.points().nth(1).unwrap().superseded_by, 1.0);
}
