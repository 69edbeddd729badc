//! The controller's contact with the world at run time (issue 26): what an upper computer or a
//! camera process sends to a running `ttctl`, and what it answers. For now the datagram format
//! ([`wire`]); the hit and ball modes build on it.

pub mod wire;
