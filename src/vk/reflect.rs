//! Just enough SPIR-V reflection to check a shader against its pass's declarations: the format qualifier
//! of every storage image (set, binding). One that differs from the bound image's format is undefined
//! behaviour in Vulkan (it once read an RGBA32F target as rgba16f).

use ash::vk;

const OP_TYPE_IMAGE: u32 = 25;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;
/// OpTypeImage's Sampled operand for storage images.
const SAMPLED_STORAGE: u32 = 2;

/// (set, binding, SPIR-V ImageFormat) of every storage image variable.
pub fn storage_image_formats(words: &[u32]) -> Vec<(u32, u32, u32)> {
    use std::collections::HashMap;
    let (mut images, mut pointers, mut vars) = (HashMap::new(), HashMap::new(), Vec::new());
    let (mut sets, mut bindings) = (HashMap::new(), HashMap::new());
    let mut i = 5; // after the header
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let ins = &words[i..(i + count.max(1)).min(words.len())];
        match op {
            OP_TYPE_IMAGE if ins.len() >= 9 && ins[7] == SAMPLED_STORAGE => {
                images.insert(ins[1], ins[8]);
            }
            OP_TYPE_POINTER if ins.len() >= 4 => {
                pointers.insert(ins[1], ins[3]);
            }
            OP_VARIABLE if ins.len() >= 3 => vars.push((ins[2], ins[1])),
            OP_DECORATE if ins.len() >= 4 && ins[2] == DECORATION_BINDING => {
                bindings.insert(ins[1], ins[3]);
            }
            OP_DECORATE if ins.len() >= 4 && ins[2] == DECORATION_DESCRIPTOR_SET => {
                sets.insert(ins[1], ins[3]);
            }
            _ => {}
        }
        i += count.max(1);
    }
    let mut out: Vec<(u32, u32, u32)> = vars
        .into_iter()
        .filter_map(|(var, ptr)| {
            let format = images.get(pointers.get(&ptr)?)?;
            Some((*sets.get(&var)?, *bindings.get(&var)?, *format))
        })
        .collect();
    out.sort();
    out
}

/// The SPIR-V ImageFormat a storage image of `format` must be declared with (None: not bound as storage).
pub fn spirv_image_format(format: vk::Format) -> Option<u32> {
    Some(match format {
        vk::Format::R32G32B32A32_SFLOAT => 1,
        vk::Format::R16G16B16A16_SFLOAT => 2,
        vk::Format::R32_SFLOAT => 3,
        vk::Format::R8G8B8A8_UNORM => 4,
        vk::Format::R8G8B8A8_SNORM => 5,
        vk::Format::R32G32_SFLOAT => 6,
        vk::Format::R16G16_SFLOAT => 7,
        vk::Format::R16G16B16A16_UNORM => 10,
        vk::Format::R32_UINT => 33,
        vk::Format::R32G32_UINT => 35,
        _ => return None,
    })
}
