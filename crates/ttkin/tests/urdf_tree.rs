//! URDF structure checks (issue 14): the links must form a tree; loops, two parents and
//! undeclared links are refused with a message naming the problem, never accepted or looped on.

use ttkin::{urdf, Error};

fn joint(name: &str, parent: &str, child: &str) -> String {
    format!(
        r#"<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>
           <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#
    )
}

fn robot(links: &[&str], joints: &[String]) -> String {
    let links: String = links.iter().map(|l| format!(r#"<link name="{l}"/>"#)).collect();
    format!(r#"<robot name="r">{links}{}</robot>"#, joints.concat())
}

#[test]
fn a_loop_of_two_joints_is_refused() {
    let text = robot(&["a", "b"], &[joint("ab", "a", "b"), joint("ba", "b", "a")]);
    for (base, tip) in [("a", "b"), ("b", "a")] {
        let e = urdf::from_urdf_str(&text, base, tip).unwrap_err();
        assert!(matches!(e, Error::Urdf(_)) && e.to_string().contains("loop"), "{e}");
    }
}

#[test]
fn a_loop_away_from_the_base_is_refused_not_walked_forever() {
    // c is the base; the tip b sits on the loop a → b → a, which never reaches c.
    let text = robot(&["a", "b", "c"], &[joint("ab", "a", "b"), joint("ba", "b", "a")]);
    let e = urdf::from_urdf_str(&text, "c", "b").unwrap_err();
    assert!(e.to_string().contains("loop"), "{e}");
    let text = robot(
        &["a", "b", "c", "d"],
        &[
            joint("cd", "c", "d"),
            joint("ab", "a", "b"),
            joint("bc", "b", "c"),
            joint("ca", "c", "a"),
        ],
    );
    let e = urdf::from_urdf_str(&text, "a", "d").unwrap_err();
    assert!(e.to_string().contains("loop"), "{e}");
}

#[test]
fn two_parents_and_undeclared_links_are_refused() {
    let text = robot(&["a", "b", "c"], &[joint("ab", "a", "b"), joint("cb", "c", "b")]);
    let e = urdf::from_urdf_str(&text, "a", "b").unwrap_err();
    assert!(e.to_string().contains("two parent joints"), "{e}");
    let text = robot(&["a", "b"], &[joint("ab", "a", "b"), joint("bz", "b", "zzz")]);
    let e = urdf::from_urdf_str(&text, "a", "b").unwrap_err();
    assert!(e.to_string().contains("undeclared link 'zzz'"), "{e}");
}

#[test]
fn a_tree_still_reads() {
    let text = robot(
        &["a", "b", "c", "d"],
        &[joint("ab", "a", "b"), joint("bc", "b", "c"), joint("bd", "b", "d")],
    );
    let chain = urdf::from_urdf_str(&text, "a", "c").unwrap();
    assert_eq!(chain.dof(), 2);
}

// Issue 29: parser limits and the robot file's checks on every URDF value.

#[test]
fn nesting_beyond_the_depth_limit_is_refused_before_parsing() {
    // 20,000 levels overflowed the parser's stack (a segfault); now a message.
    let deep = format!(
        "<robot name=\"r\">{}{}</robot>",
        "<a>".repeat(20_000),
        "</a>".repeat(20_000)
    );
    let e = urdf::from_urdf_str(&deep, "a", "b").unwrap_err();
    assert!(e.to_string().contains("nested more than 64"), "{e}");
    // Comments, quotes with '>' and self-closing tags do not count as levels.
    let text = robot(&["a", "b"], &[joint("ab", "a", "b")])
        .replace("<robot name=\"r\">", "<robot name=\"r\"><!-- <x><y><z> --><?pi x?>");
    assert!(urdf::from_urdf_str(&text, "a", "b").is_ok());
}

#[test]
fn a_long_chain_is_checked_in_linear_time_and_too_many_joints_are_refused() {
    // 3000 joints in a line: the loop check walked each link to the root and searched the walk
    // (cubic, 287 s at 10,000 joints); now each link is walked once.
    let n = 3000;
    let links: Vec<String> = (0..=n).map(|i| format!("l{i}")).collect();
    let link_refs: Vec<&str> = links.iter().map(String::as_str).collect();
    let joints: Vec<String> = (0..n)
        .map(|i| joint(&format!("j{i}"), &links[i], &links[i + 1]))
        .collect();
    let text = robot(&link_refs, &joints);
    let chain = urdf::from_urdf_str(&text, "l0", &format!("l{n}")).unwrap();
    assert_eq!(chain.dof(), n);
    let joints: Vec<String> = (0..5000).map(|i| joint(&format!("j{i}"), "a", "b")).collect();
    let e = urdf::from_urdf_str(&robot(&["a", "b"], &joints), "a", "b").unwrap_err();
    assert!(e.to_string().contains("more than the 4096"), "{e}");
}

#[test]
fn urdf_values_the_robot_file_refuses_are_refused() {
    let base = robot(&["a", "b"], &[joint("ab", "a", "b")]);
    let cases = [
        (r#"lower="-1" upper="1""#, r#"lower="1" upper="-1""#, "above upper"),
        (r#"velocity="1""#, r#"velocity="-1""#, "velocity = -1"),
        (r#"effort="1""#, r#"effort="-2""#, "effort = -2"),
        (r#"effort="1""#, r#"effort="nan""#, "effort = NaN"),
    ];
    for (from, to, msg) in cases {
        let text = base.replace(from, to);
        let e = urdf::from_urdf_str(&text, "a", "b").unwrap_err();
        assert!(e.to_string().contains(msg), "{to}: {e}");
    }
    let neg_mass = base.replace(
        r#"<link name="b"/>"#,
        r#"<link name="b"><inertial><mass value="-1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>"#,
    );
    let e = urdf::from_urdf_str(&neg_mass, "a", "b").unwrap_err();
    assert!(e.to_string().contains("mass must be > 0"), "{e}");
    let dup = base.replace(r#"<link name="b"/>"#, r#"<link name="b"/><link name="a"/>"#);
    let e = urdf::from_urdf_str(&dup, "a", "b").unwrap_err();
    assert!(e.to_string().contains("two links are named 'a'"), "{e}");
    let nan_origin = base.replace(
        r#"<axis xyz="0 0 1"/>"#,
        r#"<origin xyz="0 0 0" rpy="nan 0 0"/><axis xyz="0 0 1"/>"#,
    );
    let e = urdf::from_urdf_str(&nan_origin, "a", "b").unwrap_err();
    assert!(e.to_string().contains("origin of joint 'ab'"), "{e}");
    // A massless link and a missing acceleration limit still read.
    assert!(urdf::from_urdf_str(&base, "a", "b").is_ok());
}

#[test]
fn a_nan_origin_in_a_robot_file_is_refused() {
    let text = r#"
name = "r"
[[joint]]
name = "j1"
type = "revolute"
origin = { xyz = [0, 0, 0], rpy = [nan, 0, 0] }
"#;
    let e = ttkin::description::from_toml_str(text, "<test>").unwrap_err();
    assert!(e.to_string().contains("origin rotation of joint 'j1'"), "{e}");
}
