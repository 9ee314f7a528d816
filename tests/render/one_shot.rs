//! `Context::one_shot` from two threads at once, each with its own validated
//! context, as the test harness runs them. Khronos validation 1.3.239
//! corrupts its heap when labelled command buffers are freed while another
//! thread labels new ones (Vulkan-ValidationLayers issue 5172): one_shot
//! freeing its command buffer after each submission crashed this test in 2 of
//! 3 runs (SIGSEGV, SIGABRT: "malloc_consolidate(): unaligned fastbin chunk
//! detected") on the 2-core VM, and the whole render suite now and then (in
//! the validation layer's vkCmdBeginDebugUtilsLabelEXT, during an upload).
//! one_shot now reuses its command buffers.
use crate::common;

#[test]
fn one_shot_from_two_threads_under_validation_survives() {
    let threads: Vec<_> = (0..2)
        .map(|t| {
            std::thread::spawn(move || {
                let ctx = common::validated_context();
                for i in 0..30000 {
                    ctx.one_shot(&format!("one shot {t}/{i}"), |_| Ok(())).unwrap();
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
}
