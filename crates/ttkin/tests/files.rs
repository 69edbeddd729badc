//! Robot files and URDF: round trips and errors, from Rust.

mod common;

use common::*;
use proptest::prelude::*;
use ttkin::{description, urdf, Error};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(50))]

    #[test]
    fn urdf_and_toml_round_trips_keep_fk(u in prop::collection::vec(0.0..1.0f64, 8)) {
        for chain in robots() {
            let tool = ttkin::transform::from_xyz_rpy([0.02, -0.01, 0.15], [0.3, 1.2, -0.4]);
            let base = ttkin::transform::from_xyz_rpy([0.5, 0.1, 0.0], [0.0, 0.0, 0.7]);
            let chain = chain.with_tool(tool).unwrap().with_base(base).unwrap();
            let q = config_from_unit(&chain, &u);
            let from_urdf = urdf::from_urdf_str(&urdf::to_urdf_string(&chain), urdf::BASE_LINK, urdf::TOOL_LINK).unwrap();
            let from_toml = description::from_toml_str(&description::to_toml(&chain), "test").unwrap();
            let t = chain.fk(&q).unwrap();
            prop_assert!(pose_diff(&t, &from_urdf.fk(&q).unwrap()) < 1e-12);
            prop_assert!(pose_diff(&t, &from_toml.fk(&q).unwrap()) < 1e-12);
            // URDF 1.0 has no acceleration limits: compare the rest.
            for (a, b) in from_urdf.limits().iter().zip(chain.limits()) {
                prop_assert_eq!((a.lower, a.upper, a.velocity, a.effort), (b.lower, b.upper, b.velocity, b.effort));
            }
            prop_assert_eq!(from_toml.limits(), chain.limits());
        }
    }
}

#[test]
fn urdf_errors_name_the_problem() {
    let text = r#"<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
        <joint name="j" type="floating"><parent link="a"/><child link="b"/></joint></robot>"#;
    let e = urdf::from_urdf_str(text, "a", "b").unwrap_err();
    assert!(matches!(e, Error::Urdf(_)) && e.to_string().contains("Floating"), "{e}");
    let e = urdf::from_urdf_str(text, "a", "c").unwrap_err();
    assert!(e.to_string().contains("not connected"), "{e}");
    let e = urdf::from_urdf_str(text, "a", "zzz").unwrap_err();
    assert!(e.to_string().contains("no link named 'zzz'"), "{e}");
    assert!(urdf::from_urdf_str("<robot", "a", "b").is_err());
    assert!(matches!(
        urdf::load("/nonexistent/robot.urdf", "a", "b"),
        Err(Error::File { .. })
    ));
}

#[test]
fn robot_file_errors_name_the_problem() {
    let e = description::from_toml_str("name = 'x'\n[[joint]]\nname = 'a'\ntype = 'revolute'\n", "t").unwrap_err();
    assert!(e.to_string().contains("exactly one of 'dh' or 'origin'"), "{e}");
    let e = description::from_toml_str(
        "name = 'x'\nconvention = 'modified'\n[[joint]]\nname = 'a'\ntype = 'revolute'\ndh = {}\n[[joint]]\nname = 'a'\ntype = 'revolute'\ndh = {}\n",
        "t",
    )
    .unwrap_err();
    assert!(e.to_string().contains("used twice"), "{e}");
    assert!(matches!(
        description::load("/nonexistent.toml"),
        Err(Error::File { .. })
    ));
}

#[test]
fn robot_facts_are_data_that_robot_files_carry() {
    // The racket mount and the ready configuration belong to the robot, not to a name match.
    let m8 = ttkin::robots::mobile8();
    assert_eq!(*m8.racket(), ttkin::hit::RacketMount::seed000().in_tool);
    assert_eq!(m8.ready(), ttkin::robots::mobile8_start().to_vec());
    assert_eq!(ttkin::robots::gantry6().ready(), ttkin::robots::GANTRY6_READY.to_vec());
    // Gravity too (base frame): mobile8's base frame has x up, the others z up.
    assert_eq!(m8.gravity(), ttkin::robots::MOBILE8_GRAVITY);
    assert_eq!(ttkin::robots::gantry6().gravity(), ttkin::dynamics::EARTH_GRAVITY);
    let m8_file = description::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../../robots/mobile8.toml")).unwrap();
    assert_eq!(m8_file.gravity(), ttkin::robots::MOBILE8_GRAVITY);
    for chain in robots() {
        let back = description::from_toml_str(&description::to_toml(&chain), "test").unwrap();
        assert!(pose_diff(back.racket(), chain.racket()) < 1e-15, "{}", chain.name());
        assert_eq!(back.ready(), chain.ready(), "{}", chain.name());
        assert_eq!(back.has_ready(), chain.has_ready(), "{}", chain.name());
        // A renamed copy keeps them: nothing is looked up by name.
        let renamed = description::from_toml_str(
            &description::to_toml(&chain).replacen(&format!("name = \"{}\"", chain.name()), "name = \"copy\"", 1),
            "test",
        )
        .unwrap();
        assert!(pose_diff(renamed.racket(), chain.racket()) < 1e-15);
        assert_eq!(renamed.ready(), chain.ready());
        assert_eq!(back.gravity(), chain.gravity(), "{}", chain.name());
        assert_eq!(renamed.gravity(), chain.gravity());
        let planner = ttkin::hit::HitPlanner::new(&renamed, Default::default()).unwrap();
        assert_eq!(planner.gravity(), chain.gravity());
        assert_eq!(planner.default_ready(), &chain.ready()[..]);
        assert!(pose_diff(&planner.mount().in_tool, chain.racket()) < 1e-15);
    }
    // Units as typed; a ready pose outside the limits or of the wrong length is refused.
    let text = r#"
        name = "one"
        units = { angle = "deg" }
        racket = { xyz = [0, 0, 0.1], rpy = [0, 90, 0] }
        ready = [30]
        [[joint]]
        name = "j"
        type = "revolute"
        dh = { a = 0.3 }
        convention = "standard"
        limits = { lower = -90, upper = 90 }
    "#;
    let c = description::from_toml_str(text, "one").unwrap();
    assert!((c.ready()[0] - 30f64.to_radians()).abs() < 1e-15);
    assert!((c.racket().translation.vector.z - 0.1).abs() < 1e-15);
    let e = description::from_toml_str(&text.replace("ready = [30]", "ready = [120]"), "one").unwrap_err();
    assert!(
        e.to_string().contains("ready") && e.to_string().contains("limits"),
        "{e}"
    );
    let e = description::from_toml_str(&text.replace("ready = [30]", "ready = [1, 2]"), "one").unwrap_err();
    assert!(e.to_string().contains("ready"), "{e}");
    let e = description::from_toml_str(&text.replace("ready = [30]", "ready = [nan]"), "one").unwrap_err();
    assert!(e.to_string().contains("ready"), "{e}");
}
