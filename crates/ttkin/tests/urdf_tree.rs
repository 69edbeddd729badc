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
