//! Device creation, device listing, and the GPU timer.

use crate::common;

use speculum::vk::{list_devices, Context, ContextDesc, GpuTimer};

/// A context comes up with validation on and names a device that `list_devices` lists.
#[test]
fn context_creates_with_validation_and_lists_its_device() {
    let ctx = common::context();
    assert!(ctx.validation_enabled());
    assert!(!ctx.device_name.is_empty());
    let list = list_devices().unwrap();
    assert!(list.iter().any(|d| d.name == ctx.device_name && d.usable.is_ok()));
    assert!(ctx.timestamp_valid_bits > 0 && ctx.timestamp_period_ns > 0.0);
}

/// `--device` with an index or name that matches nothing is an error naming the choice.
#[test]
fn unknown_device_is_a_clear_error() {
    for wanted in ["no-such-gpu-xyz", "999"] {
        let err = Context::new(&ContextDesc {
            validation: false,
            device: Some(wanted.into()),
            ..Default::default()
        })
        .err()
        .expect("no device should match");
        let msg = err.to_string();
        assert!(msg.contains(wanted), "{msg}");
    }
}

/// Picking the device by its listed index or by a name substring selects it.
#[test]
fn device_selects_by_index_and_name() {
    let list = list_devices().unwrap();
    let first = list.iter().find(|d| d.usable.is_ok()).expect("a usable device");
    let by_index = Context::new(&ContextDesc {
        validation: false,
        device: Some(first.index.to_string()),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(by_index.device_name, first.name);
    let needle: String = first.name.chars().take(6).collect::<String>().to_uppercase();
    let by_name = Context::new(&ContextDesc {
        validation: false,
        device: Some(needle),
        ..Default::default()
    })
    .unwrap();
    assert!(by_name
        .device_name
        .to_uppercase()
        .contains(&first.name.chars().take(6).collect::<String>().to_uppercase()));
}

/// Nested named scopes come back by name, with the outer scope at least as long as the inner.
#[test]
fn timer_scopes_report_by_name() {
    let ctx = common::context();
    let mut timer = GpuTimer::new(&ctx, 4).unwrap();
    let data = vec![7u8; 1 << 20];
    let src = speculum::vk::Buffer::with_data(&ctx, "src", ash::vk::BufferUsageFlags::TRANSFER_SRC, &data).unwrap();
    let dst = speculum::vk::Buffer::new(
        &ctx,
        "dst",
        data.len() as u64,
        ash::vk::BufferUsageFlags::TRANSFER_DST | ash::vk::BufferUsageFlags::TRANSFER_SRC,
        gpu_allocator::MemoryLocation::GpuOnly,
    )
    .unwrap();
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        timer.begin(cmd, "outer");
        timer.begin(cmd, "copy");
        let region = ash::vk::BufferCopy::default().size(data.len() as u64);
        // SAFETY: `cmd` is recording; both buffers are live and `data.len()` bytes or more.
        unsafe { ctx.device.cmd_copy_buffer(cmd, src.raw, dst.raw, &[region]) };
        timer.end(cmd, "copy");
        timer.end(cmd, "outer");
    })
    .unwrap();
    let results = timer.results().unwrap();
    let names: Vec<_> = results.iter().map(|r| r.0).collect();
    assert_eq!(names, ["outer", "copy"]);
    assert!(results[1].1 > 0.0, "a 1 MiB copy takes measurable time");
    assert!(results[0].1 >= results[1].1);
    assert_eq!(dst.read().unwrap(), data, "the copy itself ran");
}

/// A pipeline created for push constants other than the shader's block is refused with
/// an error naming both sizes; the right type is accepted.
#[test]
fn pipeline_push_type_must_match_the_shader() {
    use speculum::vk::Pipeline;
    let ctx = common::context();
    let shader = speculum::shaders::COMPOSE_COMP;
    let err = Pipeline::compute::<[u32; 2]>(&ctx, "test.compose", shader)
        .err()
        .expect("8 B of push constants for a 20 B block must be refused");
    let msg = err.to_string();
    assert!(msg.contains("20 B") && msg.contains("8 B"), "{msg}");
    assert!(Pipeline::compute::<speculum::passes::compose::ComposePush>(&ctx, "test.compose", shader).is_ok());
    assert!(Pipeline::compute::<u32>(&ctx, "test.light", speculum::shaders::LIGHT_DIRECT_COMP).is_ok());
}

/// Resources are bound by the shader's names, not by their place in the list: a
/// binding left without its resource (a misspelt name), a resource of another kind, or
/// two resources under one name fail the bind with a message naming the pipeline and
/// the binding, before anything is recorded. glossy.rs binds this kernel in shuffled
/// order and checks its output.
#[test]
fn bindings_go_by_name() {
    use speculum::vk::{Buffer, Pipeline, Resource};
    let ctx = common::context();
    let shader = speculum::shaders::GLOSSY_SAMPLE_COMP;
    let pipeline = Pipeline::compute::<u32>(&ctx, "test.by_name", shader).unwrap();
    let usage = ash::vk::BufferUsageFlags::STORAGE_BUFFER | ash::vk::BufferUsageFlags::UNIFORM_BUFFER;
    let [a, b, c] = ["a", "b", "c"].map(|n| Buffer::with_data(&ctx, n, usage, &[7u8; 1024]).unwrap());
    let image = speculum::vk::Image::storage(
        &ctx,
        "test.image",
        ash::vk::Extent2D { width: 4, height: 4 },
        ash::vk::Format::R32_UINT,
    )
    .unwrap();
    let cases: [(&[speculum::vk::Bind<'_>], &str); 3] = [
        (
            &[
                ("frame", Resource::Buffer(&a)),
                ("case", Resource::Buffer(&b)),
                ("directions", Resource::Buffer(&c)),
            ],
            "binding 1 `cases` (STORAGE_BUFFER) has no resource",
        ),
        (
            &[
                ("frame", Resource::Buffer(&a)),
                ("cases", Resource::StorageImage(&image)),
                ("directions", Resource::Buffer(&c)),
            ],
            "binding 1 `cases` wants STORAGE_BUFFER",
        ),
        (
            &[
                ("frame", Resource::Buffer(&a)),
                ("cases", Resource::Buffer(&b)),
                ("cases", Resource::Buffer(&c)),
            ],
            "two resources given for `cases`",
        ),
    ];
    let mut messages = Vec::new();
    ctx.one_shot(|cmd| {
        for (resources, _) in &cases {
            let bound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| pipeline.bind(cmd, resources, &1u32)));
            let err = bound.expect_err("the bind must fail");
            let msg = err.downcast_ref::<String>().cloned().unwrap_or_default();
            messages.push(msg);
        }
    })
    .unwrap();
    for (msg, (_, want)) in messages.iter().zip(&cases) {
        assert!(
            msg.contains("test.by_name") && msg.contains(want),
            "{msg:?} should say {want:?}"
        );
    }
}

/// The device limits the renderer checks against, printed for the record.
#[test]
fn device_limits_are_reported() {
    let ctx = common::context();
    let l = &ctx.limits;
    println!(
        "{}: maxComputeWorkGroupCount {:?}, maxStorageBufferRange {}, maxImageDimension2D {}",
        ctx.device_name, l.max_compute_work_group_count, l.max_storage_buffer_range, l.max_image_dimension2_d
    );
    assert!(l.max_compute_work_group_count[0] >= 65535, "Vulkan guarantees 65535");
    assert!(l.max_storage_buffer_range >= 1 << 27);
}
