use crate::scene::Warning;
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FabricParams {}
impl FabricParams {
    pub fn from_gltf_extension(_value: &serde_json::Value, _material_name: &str, _warnings: &mut Vec<Warning>) -> crate::Result<FabricParams> { Ok(FabricParams {}) }
}
