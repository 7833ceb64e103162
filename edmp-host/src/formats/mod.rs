//! The file formats, one reader and writer each, shared by the commands and the Python
//! package (docs/formats.md): the `edmp-scene/1` scene ([`json`], its fields read by path in
//! [`fields`]), the `edmp-plan/1` plan
//! ([`plan`]) and its timed `trajectory` ([`trajectory`]), MoveIt's planning scenes ([`moveit`]),
//! the `points` and `mesh` obstacles ([`surface`]) and the geometry files they name: point
//! clouds from PLY and PCD ([`cloud`]) and triangle meshes from OBJ, STL and PLY
//! ([`mesh_file`]), with their one error ([`file_error`]).

pub mod cloud;
pub mod fields;
pub mod file_error;
pub mod json;
pub mod mesh_file;
pub mod moveit;
pub mod plan;
mod ply;
#[cfg(test)]
mod robustness;
pub mod surface;
pub mod trajectory;
