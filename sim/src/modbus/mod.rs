//! Simulated Modbus RTU devices.
