//! A simulated CANopen CiA 402 servo drive.
