//! The controller's contact with the world at run time (issue 26): what an upper computer or a
//! camera process sends to a running `ttctl`, and what it answers. The datagram format
//! ([`wire`]), the seam between deciding hits and executing them ([`brain`]) and the ball mode's
//! brain ([`ball`]); the hit and ball modes build on them.

pub mod ball;
pub mod brain;
pub mod wire;
