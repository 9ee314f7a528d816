//! Device limits the renderer must respect (render size, texture size,
//! acceleration-structure sizes), queried once with the capabilities.

use ash::vk;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// maxImageDimension2D: render targets and textures.
    pub max_image_dimension_2d: u32,
    /// maxComputeWorkGroupCount[0..2]: full-screen passes dispatch 8x8 groups.
    pub max_compute_work_group_count: [u32; 3],
    /// VkPhysicalDeviceAccelerationStructurePropertiesKHR::maxPrimitiveCount
    /// (triangles in one BLAS); 0 without acceleration structures.
    pub max_primitive_count: u64,
    /// ... ::maxInstanceCount (instances in the TLAS); 0 without them.
    pub max_instance_count: u64,
}

impl Limits {
    /// Reads the limits; `has_as`: VK_KHR_acceleration_structure is present (only then may its properties
    /// struct be chained).
    pub fn query(instance: &ash::Instance, pd: vk::PhysicalDevice, has_as: bool) -> Limits {
        let mut asp = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default();
        if has_as {
            props2 = props2.push_next(&mut asp);
        }
        unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
        let l = props2.properties.limits;
        Limits {
            max_image_dimension_2d: l.max_image_dimension2_d,
            max_compute_work_group_count: l.max_compute_work_group_count,
            max_primitive_count: if has_as { asp.max_primitive_count } else { 0 },
            max_instance_count: if has_as { asp.max_instance_count } else { 0 },
        }
    }

    /// Whether a `width` x `height` frame fits: its targets and its 8x8 compute dispatches.
    pub fn check_extent(&self, width: u32, height: u32) -> anyhow::Result<()> {
        let max = self.max_image_dimension_2d;
        if width > max || height > max {
            anyhow::bail!("resolution {width}x{height} exceeds this device's maxImageDimension2D ({max})");
        }
        let groups = [width.div_ceil(8), height.div_ceil(8)];
        if groups[0] > self.max_compute_work_group_count[0]
            || groups[1] > self.max_compute_work_group_count[1]
        {
            anyhow::bail!(
                "resolution {width}x{height} needs {}x{} compute work groups, more than this device allows ({:?})",
                groups[0],
                groups[1],
                &self.max_compute_work_group_count[..2]
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Limits;

    #[test]
    fn extent_checks_name_the_limit() {
        let l = Limits {
            max_image_dimension_2d: 4096,
            max_compute_work_group_count: [65535, 100, 65535],
            max_primitive_count: 0,
            max_instance_count: 0,
        };
        assert!(l.check_extent(4096, 800).is_ok());
        let e = l.check_extent(4097, 10).unwrap_err().to_string();
        assert!(e.contains("maxImageDimension2D (4096)"), "{e}");
        let e = l.check_extent(64, 801).unwrap_err().to_string();
        assert!(e.contains("compute work groups"), "{e}");
    }
}
