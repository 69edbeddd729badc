//! The two axes (nodes 1 and 2) of the CANopen tests and bench, as the controller sees them.
#![allow(dead_code)]

use ttcan::canopen::Units;
use ttcan::runtime::master::LinkConfig;

/// Nodes 1 and 2 with the default units, a 0.05 rad following-error limit and a 10 A current limit.
pub fn two_links() -> Vec<LinkConfig> {
    (1..=2)
        .map(|n| LinkConfig {
            node: n,
            units: Units::default(),
            following_error_limit: 0.05,
            max_current: 10.0,
        })
        .collect()
}
