//! Cleanup without hand-written unwinding. A type whose `destroy` accepts still-null members (Vulkan
//! ignores null handles, and this crate's wrappers do too) is created empty and filled by [`built`]:
//! when a step fails, what exists is destroyed and the error passed on, so a `create` reads straight
//! through with `?`. The teardown leak checks (tests/render/error_paths.rs) catch any object missed.

use anyhow::Result;

use super::Context;

/// Something that releases its Vulkan objects with the context.
pub trait Destroy {
    fn destroy(&mut self, ctx: &Context);
}

/// `value` after `fill`; if `fill` fails, `value` (with whatever `fill` made) is destroyed and the error
/// returned.
pub fn built<T: Destroy>(ctx: &Context, mut value: T, fill: impl FnOnce(&mut T) -> Result<()>) -> Result<T> {
    match fill(&mut value) {
        Ok(()) => Ok(value),
        Err(e) => {
            value.destroy(ctx);
            Err(e)
        }
    }
}

impl<T: Destroy> Destroy for Vec<T> {
    fn destroy(&mut self, ctx: &Context) {
        self.iter_mut().for_each(|v| v.destroy(ctx));
        self.clear();
    }
}

/// `Destroy` for types with an inherent `destroy(&mut self, &Context)`.
#[macro_export]
macro_rules! destroy_by_method {
    ($($t:ty),* $(,)?) => {
        $(impl $crate::vk::Destroy for $t {
            fn destroy(&mut self, ctx: &$crate::vk::Context) {
                <$t>::destroy(self, ctx)
            }
        })*
    };
}
