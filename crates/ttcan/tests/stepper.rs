//! The multi-rate stepper: loops run at their rates, N axes behave like N independent ones, and the
//! plant's load can follow a changing inertia.

mod common;
use common::*;
use ttcan::{Axis, AxisConfig, Mode, Plant, Rates, Scheduler, Setpoint, Simulation, Stepper};

#[test]
fn scheduler_runs_each_loop_at_its_rate() {
    let rates = Rates::new(20_000.0, 5_000.0, 1_000.0).unwrap();
    let mut s = Scheduler::new(&rates);
    let (mut speed, mut position) = (0, 0);
    for k in 0..2000 {
        let peek = s.peek();
        let due = s.next_tick();
        assert_eq!(peek, due);
        assert_eq!(due.speed, k % 4 == 0, "tick {k}");
        assert_eq!(due.position, k % 20 == 0, "tick {k}");
        assert!(!due.position || due.speed, "position steps coincide with speed steps");
        speed += due.speed as u32;
        position += due.position as u32;
    }
    assert_eq!((speed, position), (500, 100));
    assert_eq!(s.ticks(), 2000);
}

#[test]
fn stepper_axes_match_independent_simulations() {
    // Three axes with different loads, each on its own plant, run by one stepper; the same axes
    // run one by one in `Simulation` give the same duty cycles bit for bit.
    let loads = [5e-4, 1e-3, 2e-3];
    let models: Vec<_> = loads
        .iter()
        .map(|j| {
            let mut m = model();
            m.load.inertia = *j;
            m
        })
        .collect();
    let axes: [Axis; 3] = std::array::from_fn(|k| Axis::new(&AxisConfig::new(models[k])).unwrap());
    let mut stepper = Stepper::new(axes).unwrap();
    let mut plants: Vec<Plant> = models.iter().map(|m| Plant::new(m, 5e-5).unwrap()).collect();
    let mut sims: Vec<Simulation> = models
        .iter()
        .map(|m| Simulation::new(m, &AxisConfig::new(*m)).unwrap())
        .collect();
    let mut duty = [0.0; 3];
    let reference = |k: usize, t: f64| quintic(1.0 + k as f64, 0.2, t);
    for tick in 0..6000 {
        let t = tick as f64 * 5e-5;
        let m: [ttcan::Measurement; 3] = std::array::from_fn(|k| plants[k].measure());
        if tick == 1 {
            for (k, a) in stepper.axes_mut().iter_mut().enumerate() {
                assert!(a.enable(Mode::Position));
                assert!(sims[k].axis.enable(Mode::Position));
            }
        }
        for (k, a) in stepper.axes_mut().iter_mut().enumerate() {
            let (q, qd, qdd) = reference(k, t);
            a.set_position(q, qd, qdd);
            sims[k].apply(Setpoint::Position(q, qd, qdd));
        }
        stepper.cycle(&m, &mut duty);
        for k in 0..3 {
            plants[k].step(duty[k]);
            sims[k].step();
            assert_eq!(sims[k].axis.duty(), duty[k], "axis {k}, tick {tick}");
        }
    }
    for (k, p) in plants.iter().enumerate() {
        assert!(
            (p.output_position() - (1.0 + k as f64)).abs() < 1e-3,
            "axis {k} at {}",
            p.output_position()
        );
        assert_eq!(stepper.axes()[k].fault(), None);
    }
}

#[test]
fn plant_load_inertia_can_follow_the_robot() {
    let mut m4 = model();
    m4.load.inertia = 4e-3;
    let mut changed = Plant::new(&model(), 5e-5).unwrap();
    let mut built = Plant::new(&m4, 5e-5).unwrap();
    let mut light = Plant::new(&model(), 5e-5).unwrap();
    assert!(changed.set_load_inertia(4e-3));
    assert!(!changed.set_load_inertia(-1.0));
    assert!(!changed.set_load_inertia(f64::NAN));
    assert_eq!(changed.model().load.inertia, 4e-3);
    for _ in 0..400 {
        changed.step(0.5);
        built.step(0.5);
        light.step(0.5);
        assert_eq!(changed.current(), built.current());
        assert_eq!(changed.output_speed(), built.output_speed());
    }
    assert!(
        changed.output_speed() < 0.8 * light.output_speed(),
        "the heavier load accelerates less"
    );
}
