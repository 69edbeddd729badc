//! The controller's contact with the world at run time (issue 26): what an upper computer or a
//! camera process sends to a running `ttctl`, and what it answers. The datagram format
//! ([`wire`]) and the seam between deciding hits and executing them ([`brain`]); the hit and ball
//! modes build on them.

pub mod brain;
pub mod wire;
