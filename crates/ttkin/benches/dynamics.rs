//! Criterion benchmarks of the dynamics algorithms on the seed-000 mobile manipulator (8 joints)
//! and the UR5 (6 joints).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use ttkin::dynamics::EARTH_GRAVITY;
use ttkin::{Dynamics, DynamicsData};

fn bench(c: &mut Criterion) {
    for chain in [ttkin::robots::mobile8(), ttkin::robots::ur5()] {
        let dy = Dynamics::new(&chain).unwrap();
        let mut data = DynamicsData::new(&dy);
        let n = dy.dof();
        let q: Vec<f64> = ttkin::robots::mobile8_start()[..n].to_vec();
        let qd: Vec<f64> = (0..n).map(|i| 0.3 - 0.1 * i as f64).collect();
        let qdd: Vec<f64> = (0..n).map(|i| 1.0 - 0.2 * i as f64).collect();
        let name = chain.name();
        c.bench_function(&format!("rnea/{name}"), |b| {
            b.iter(|| {
                dy.rnea(
                    &mut data,
                    black_box(&q),
                    black_box(&qd),
                    black_box(&qdd),
                    &EARTH_GRAVITY,
                    None,
                )
                .unwrap()[0]
            })
        });
        c.bench_function(&format!("mass_matrix/{name}"), |b| {
            b.iter(|| dy.mass_matrix(&mut data, black_box(&q)).unwrap()[(0, 0)])
        });
        let tau = dy.rnea(&mut data, &q, &qd, &qdd, &EARTH_GRAVITY, None).unwrap().clone();
        c.bench_function(&format!("forward_dynamics/{name}"), |b| {
            b.iter(|| {
                dy.forward_dynamics(
                    &mut data,
                    black_box(&q),
                    black_box(&qd),
                    black_box(tau.as_slice()),
                    &EARTH_GRAVITY,
                    None,
                )
                .unwrap()[0]
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
