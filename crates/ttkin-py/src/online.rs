//! `ttcan::online::wire` for Python: encode the datagrams an upper computer or a camera process
//! sends to `ttctl`, decode what it sends back. Conversion only: the format is the core's.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use ttcan::online::wire::{self, HitMsg, Message, ObservationMsg};

use crate::convert::{transform, vector};
use crate::errors::TtmanipError;

fn bytes_of<'py>(py: Python<'py>, message: &Message, seq: u64, sent: f64) -> Bound<'py, PyBytes> {
    let mut buf = [0u8; wire::MAX_LEN];
    let len = wire::encode(message, seq, sent, &mut buf);
    PyBytes::new(py, &buf[..len])
}

/// A hit datagram (version 1): hit `id`, `stroke`, hit time `t_hit` (s, controller clock),
/// racket `pose` (4×4 rigid transform, base frame, m), racket-centre `twist` (6,), sequence number `seq`, send
/// time `sent` (s, sender clock).
#[ttkin_py_guard::guarded]
#[pyfunction]
#[pyo3(signature = (id, stroke, t_hit, pose, twist, seq, sent))]
#[allow(clippy::too_many_arguments)]
fn wire_hit<'py>(
    py: Python<'py>,
    id: u32,
    stroke: u32,
    t_hit: f64,
    pose: &Bound<'py, PyAny>,
    twist: &Bound<'py, PyAny>,
    seq: u64,
    sent: f64,
) -> PyResult<Bound<'py, PyBytes>> {
    // a NaN time encodes, and the controller drops the datagram as non-finite without an answer:
    // refused here, where the caller sees it
    let t_hit = crate::args::finite("t_hit", t_hit)?;
    let sent = crate::args::finite("sent", sent)?;
    let pose = transform(pose, "pose")?;
    let t = vector(twist, "twist", 6)?;
    let twist = [t[0], t[1], t[2], t[3], t[4], t[5]];
    let m = Message::Hit(HitMsg::from_pose(id, stroke, t_hit, &pose, twist));
    Ok(bytes_of(py, &m, seq, sent))
}

/// An observation datagram (version 1): ball `id`, `camera_time` (s, camera clock), ball
/// `position` (3,) (m, world frame), sequence number `seq`, send time `sent` (s).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn wire_observation<'py>(
    py: Python<'py>,
    id: u32,
    camera_time: f64,
    position: &Bound<'py, PyAny>,
    seq: u64,
    sent: f64,
) -> PyResult<Bound<'py, PyBytes>> {
    let camera_time = crate::args::finite("camera_time", camera_time)?;
    let sent = crate::args::finite("sent", sent)?;
    let p = vector(position, "position", 3)?;
    let m = Message::Observation(ObservationMsg {
        id,
        camera_time,
        position: [p[0], p[1], p[2]],
    });
    Ok(bytes_of(py, &m, seq, sent))
}

/// A datagram decoded into a dict (`kind`, `seq`, `sent` and the kind's fields); a malformed one
/// raises `TtmanipError` saying why (truncated, oversized, magic, version, kind, non-finite).
#[ttkin_py_guard::guarded]
#[pyfunction]
fn wire_decode<'py>(py: Python<'py>, data: &[u8]) -> PyResult<Bound<'py, PyDict>> {
    let d = wire::decode(data).map_err(|e| TtmanipError::new_err(format!("datagram: {e}")))?;
    let out = PyDict::new(py);
    out.set_item("seq", d.seq)?;
    out.set_item("sent", d.sent)?;
    match d.message {
        Message::Hit(h) => {
            out.set_item("kind", "hit")?;
            out.set_item("id", h.id)?;
            out.set_item("stroke", h.stroke)?;
            out.set_item("t_hit", h.t_hit)?;
            out.set_item("rotation", h.rotation.to_vec())?;
            out.set_item("centre", h.centre.to_vec())?;
            out.set_item("twist", h.twist.to_vec())?;
        }
        Message::Observation(o) => {
            out.set_item("kind", "observation")?;
            out.set_item("id", o.id)?;
            out.set_item("camera_time", o.camera_time)?;
            out.set_item("position", o.position.to_vec())?;
        }
        Message::Status(s) => {
            out.set_item("kind", "status")?;
            out.set_item("id", s.id)?;
            out.set_item("status", format!("{:?}", s.status))?;
            out.set_item("earliest_t_hit", s.earliest_t_hit)?;
            out.set_item("t_hit", s.t_hit)?;
            out.set_item("planning_time", s.planning_time)?;
        }
        Message::Telemetry(t) => {
            out.set_item("kind", "telemetry")?;
            out.set_item("time", t.time)?;
            out.set_item("cycle", t.cycle)?;
            out.set_item("faults", t.faults)?;
            let n = t.joints as usize;
            out.set_item("q", t.q[..n].to_vec())?;
            out.set_item("qd", t.qd[..n].to_vec())?;
        }
    }
    Ok(out)
}

/// Adds the datagram functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("WIRE_VERSION", wire::VERSION)?;
    m.add("WIRE_MAX_LEN", wire::MAX_LEN)?;
    m.add_function(wrap_pyfunction!(wire_hit, m)?)?;
    m.add_function(wrap_pyfunction!(wire_observation, m)?)?;
    m.add_function(wrap_pyfunction!(wire_decode, m)?)?;
    Ok(())
}
