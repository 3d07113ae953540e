//! OBJ loading through `tobj` (STUB: being written).
use crate::error::SceneError;
use crate::mesh::Mesh;

pub fn gunzip(path: &str, bytes: &[u8]) -> Result<Vec<u8>, SceneError> {
    let _ = (path, bytes);
    todo!("obj loader")
}

pub fn parse_obj(path: &str, bytes: &[u8]) -> Result<Mesh, SceneError> {
    let _ = (path, bytes);
    todo!("obj loader")
}
