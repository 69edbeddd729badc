//! Virtual drive.
