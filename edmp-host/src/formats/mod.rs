//! The file formats, one reader and writer each, shared by the commands and the Python
//! package (docs/formats.md): the `edmp-scene/1` scene ([`json`]), the `edmp-plan/1` plan
//! ([`plan`]) and its timed `trajectory` ([`trajectory`]), and MoveIt's planning scenes ([`moveit`]).

pub mod json;
pub mod moveit;
pub mod plan;
pub mod trajectory;
