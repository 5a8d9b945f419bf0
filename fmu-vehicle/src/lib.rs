//! A metro vehicle on an irregular straight track, with virtual inertial sensors, as an FMI 2.0
//! co-simulation FMU (work in progress).

pub mod contact;
pub mod track;
