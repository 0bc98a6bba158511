//! Simulated axes behind the axis boundary trait.
