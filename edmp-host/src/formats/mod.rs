//! The file formats, one reader and writer each, shared by the commands and the Python
//! package (docs/formats.md): the `edmp-scene/1` scene and `edmp-plan/1` plan ([`json`]), the
//! plan's timed `trajectory` ([`trajectory`]), and MoveIt's planning scenes ([`moveit`]).

pub mod json;
pub mod moveit;
pub mod trajectory;
