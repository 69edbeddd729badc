use nalgebra::Vector3;
use ttkin::ball::flight::{BallState, EventKind, Flight};
use ttkin::ball::hitplan::{shoot, HitPlanner};
use ttkin::ball::rally;
#[test]
fn dbg() {
    let pl = HitPlanner::new(ttkin::robots::gantry6(), Flight::default()).unwrap();
    let f = pl.flight;
    let mut rng = fastrand::Rng::with_seed(5);
    for i in 0..60 {
        let s = rally::serve(&f, &mut rng, 40.0);
        let plan = pl.plan(&s, 0.23, [0.9, 0.0]).unwrap();
        if plan.status.name() != "no_return" {
            continue;
        }
        // find a candidate: first in-box state after bounce
        let (mut cur, mut bounced) = (s, false);
        while cur.t < 2.0 {
            let (n, ev) = f.advance(&cur, cur.t + 0.005, None);
            cur = n;
            if ev.is_some_and(|e| e.kind == EventKind::Table) {
                bounced = true;
                continue;
            }
            if bounced && pl.reach.contains(&cur.p) {
                break;
            }
        }
        let goal = Vector3::new(0.9, 0.0, 0.02);
        for tf in pl.return_times {
            let mut spin = -cur.w;
            for it in 0..4 {
                let v = shoot(&f, &cur.p, &spin, &goal, tf);
                let Some(v) = v else {
                    eprintln!("{i} tf {tf} it {it}: shoot failed");
                    break;
                };
                let r = pl.racket.solve(&f.model, &cur.v, &cur.w, &v);
                let Ok(r) = r else {
                    eprintln!(
                        "{i} tf {tf} it {it}: racket {:?} vin {:?} w {:?} vout {:?}",
                        r.err(),
                        cur.v,
                        cur.w,
                        v
                    );
                    break;
                };
                spin = r.spin_out;
                let out = BallState {
                    v,
                    w: r.spin_out,
                    ..cur
                };
                let (_, ev) = f.run(&out, cur.t + tf + 0.5, None);
                eprintln!(
                    "{i} tf {tf} it {it}: first {:?} at {:?} spin {:?}",
                    ev.first().map(|e| e.kind),
                    ev.first().map(|e| e.before.p),
                    r.spin_out
                );
            }
        }
    }
}
