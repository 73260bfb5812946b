//! Vulkan niceties: every object carries a debug name the validation layer sees, and the pipeline cache is
//! saved to disk, read back by the next context, and a damaged or foreign cache file is ignored with a note;
//! so is the SPIR-V of the kernels compiled for a scene.

mod common;

use std::path::{Path, PathBuf};

use common::*;
use ppm_vk_device::{Buffer, BufferKind};
use ppm_vk_engine::{Context, ContextOptions, Renderer, Settings};

/// A validated context whose pipeline cache lives in `dir`.
fn cached_ctx(dir: &Path) -> Context {
    Context::new(&ContextOptions {
        validation: true,
        pipeline_cache: Some(dir.to_path_buf()),
        ..ContextOptions::default()
    })
    .expect("opening a validated context with a pipeline cache")
}

/// Creates every pipeline a render of cornell-spheres uses.
fn make_pipelines(ctx: &Context) {
    Renderer::new(
        ctx,
        &cornell(8, 8),
        Settings {
            photons_per_pass: 1000,
            ..Settings::default()
        },
    )
    .unwrap();
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-vk-vulkan-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The one pipeline cache file in `dir` (beside the folder of compiled SPIR-V).
fn cache_file(dir: &Path) -> PathBuf {
    let files: Vec<PathBuf> = (std::fs::read_dir(dir).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    assert_eq!(
        files.len(),
        1,
        "expected one cache file in {}: {files:?}",
        dir.display()
    );
    files[0].clone()
}

/// The layer names objects by their debug names in its messages: a misused buffer's message must name it
/// and the command buffer it was recorded in, which proves the names reached Vulkan.
#[test]
fn validation_messages_name_the_objects() {
    let ctx = ctx();
    assert!(
        ctx.names_objects(),
        "VK_EXT_debug_utils is not on although validation is"
    );
    // An upload buffer is only a copy source: filling it breaks VUID-vkCmdFillBuffer-dstBuffer-00029 (no
    // TRANSFER_DST usage), which the layer reports naming the buffer and the command buffer. The fill stays
    // inside the buffer, so running it is harmless.
    let buffer = Buffer::new(&ctx, "the misused buffer", 64, BufferKind::Upload).unwrap();
    assert_clean(&ctx);
    ctx.run(|cmd| {
        buffer.cmd_fill(cmd, 0);
        Ok(())
    })
    .unwrap();
    let msgs = ctx.validation_messages();
    println!("the layer said: {msgs:#?}");
    assert!(
        msgs.iter().any(|m| m.contains("00029")),
        "the misuse went unreported: {msgs:?}"
    );
    assert!(
        msgs.iter().any(|m| m.contains("the misused buffer")),
        "the buffer's name is not in {msgs:?}"
    );
    assert!(
        msgs.iter().any(|m| m.contains("Context::run")),
        "the command buffer's name is not in {msgs:?}"
    );
}

/// Naming every kind of object a render makes (and a name with a NUL inside) is itself clean.
#[test]
fn naming_is_validation_clean() {
    let ctx = ctx();
    make_pipelines(&ctx);
    let buffer = Buffer::new(&ctx, "a name\0with a NUL inside", 16, BufferKind::Storage).unwrap();
    ctx.name_object(buffer.raw(), "\0");
    ctx.name_object(buffer.raw(), "");
    drop(buffer);
    assert_clean(&ctx);
}

#[test]
fn pipeline_cache_is_saved_and_read_back() {
    let dir = scratch("roundtrip");
    let ctx = cached_ctx(&dir);
    assert_eq!(
        (ctx.pipeline_cache_loaded_bytes(), ctx.pipeline_cache_note()),
        (0, None),
        "an empty directory"
    );
    make_pipelines(&ctx);
    let written = ctx.save_pipeline_cache().unwrap().map(Path::to_path_buf);
    assert_eq!(written.as_deref(), Some(cache_file(&dir).as_path()));
    assert_eq!(
        ctx.save_pipeline_cache().unwrap(),
        None,
        "a second save with nothing new wrote again"
    );
    assert_clean(&ctx);
    drop(ctx);

    // The file: the wrapper (28 bytes), then Vulkan's own VkPipelineCacheHeaderVersionOne (32 bytes: its
    // size, version 1, vendor, device, UUID) and the driver's data.
    let bytes = std::fs::read(cache_file(&dir)).unwrap();
    assert_eq!(&bytes[..8], b"PPMVKPC\0");
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    assert!(
        word(28) >= 32 && word(32) == 1,
        "Vulkan header size {} version {}",
        word(28),
        word(32)
    );
    println!(
        "cache file: {} bytes, vendor {:#x} device {:#x}",
        bytes.len(),
        word(36),
        word(40)
    );

    let again = cached_ctx(&dir);
    assert_eq!(again.pipeline_cache_note(), None);
    assert_eq!(
        again.pipeline_cache_loaded_bytes(),
        bytes.len() - 28,
        "the second context did not load the file"
    );
    make_pipelines(&again);
    assert_clean(&again);
    drop(again);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Random bytes, a truncated file and a file from another driver build (its UUID changed, the checksum
/// made to match) are each ignored with a note: no error, no validation message, and the next save
/// replaces the file with a good one.
#[test]
fn damaged_or_foreign_cache_files_are_ignored() {
    let dir = scratch("damaged");
    let ctx = cached_ctx(&dir);
    make_pipelines(&ctx);
    drop(ctx); // saves on drop
    let path = cache_file(&dir);
    let good = std::fs::read(&path).unwrap();

    let mut noise = vec![0u8; 4096];
    let mut x = 0x2545_f491u32;
    for b in noise.iter_mut() {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        *b = x as u8;
    }
    let mut foreign = good.clone();
    foreign[28 + 16] ^= 0xff; // the first byte of pipelineCacheUUID
    let crc = crc32fast::hash(&foreign[28..]);
    foreign[24..28].copy_from_slice(&crc.to_le_bytes());
    let cases = [
        ("random bytes", noise, "not a ppm-vk pipeline cache"),
        ("truncated", good[..good.len() / 2].to_vec(), "truncated"),
        ("another driver build", foreign, "pipelineCacheUUID"),
    ];
    for (what, bytes, why) in cases {
        std::fs::write(&path, &bytes).unwrap();
        let ctx = cached_ctx(&dir);
        let note = ctx.pipeline_cache_note().unwrap_or_else(|| panic!("{what}: no note"));
        assert!(
            note.contains(why) && note.contains(&path.display().to_string()),
            "{what}: {note}"
        );
        assert_eq!(ctx.pipeline_cache_loaded_bytes(), 0, "{what}: used");
        make_pipelines(&ctx);
        assert_clean(&ctx);
        ctx.save_pipeline_cache().unwrap();
        drop(ctx);
        let ctx = cached_ctx(&dir);
        assert!(
            ctx.pipeline_cache_note().is_none() && ctx.pipeline_cache_loaded_bytes() > 0,
            "{what}: not replaced"
        );
        assert_clean(&ctx);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Off (the default, and what the other tests use) means no cache: nothing loaded, nothing saved, no note.
#[test]
fn pipeline_cache_off_saves_nothing() {
    let ctx = ctx();
    make_pipelines(&ctx);
    assert_eq!(ctx.save_pipeline_cache().unwrap(), None);
    assert_eq!(
        (ctx.pipeline_cache_loaded_bytes(), ctx.pipeline_cache_note()),
        (0, None)
    );
    assert_clean(&ctx);
}

/// The kernels compiled for a scene: each one's SPIR-V is cached beside the pipeline cache, a second
/// renderer reads it back instead of compiling, and a file truncated, damaged (its payload flipped) or
/// copied over another kernel's is compiled again, said in a note, and replaced. The image is the same
/// bit for bit every time: a cached or recompiled kernel is the kernel.
#[test]
fn compiled_kernels_are_cached_and_damaged_entries_compiled_again() {
    let dir = scratch("spirv");
    let settings = || Settings {
        photons_per_pass: 2000,
        ..Settings::default()
    };
    // The image after two passes, and each compiled kernel: (name, from the cache, note).
    let render = || {
        let ctx = cached_ctx(&dir);
        let mut r = Renderer::new(&ctx, &cornell(16, 16), settings()).unwrap();
        r.pass().unwrap();
        r.pass().unwrap();
        let image = pixels_sha256(&r.image().unwrap());
        let kernels: Vec<(String, bool, Option<String>)> = (r.setup_times().kernels.iter())
            .filter_map(|k| k.spirv_cached.map(|c| (k.name.clone(), c, k.note.clone())))
            .collect();
        drop(r);
        assert_clean(&ctx);
        (image, kernels)
    };
    let files = || -> Vec<PathBuf> {
        let mut f: Vec<PathBuf> = std::fs::read_dir(dir.join("spirv"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        f.sort();
        f
    };
    let (image, first) = render();
    // cornell-spheres: ray and photon with the scene inlined, probe and gather of one hit point a thread.
    assert!(first.len() >= 4, "{first:?}");
    assert!(
        first.iter().all(|(_, cached, note)| !cached && note.is_none()),
        "{first:?}"
    );
    assert_eq!(files().len(), first.len(), "one file per compiled kernel");

    let (again, second) = render();
    assert_eq!(again, image, "the cached kernels render another image");
    assert!(
        second.iter().all(|(_, cached, note)| *cached && note.is_none()),
        "{second:?}"
    );

    let f = files();
    let whole = std::fs::read(&f[0]).unwrap();
    std::fs::write(&f[0], &whole[..whole.len() / 2]).unwrap();
    let mut flipped = std::fs::read(&f[1]).unwrap();
    *flipped.last_mut().unwrap() ^= 0x10;
    std::fs::write(&f[1], &flipped).unwrap();
    std::fs::copy(&f[3], &f[2]).unwrap();
    let (third_image, third) = render();
    assert_eq!(third_image, image, "a damaged cache gave another image");
    let notes: Vec<&str> = third.iter().filter_map(|(_, _, n)| n.as_deref()).collect();
    assert_eq!(notes.len(), 3, "{third:?}");
    assert_eq!(third.iter().filter(|(_, cached, _)| *cached).count(), third.len() - 3);
    for (why, file) in [("truncated", &f[0]), ("checksum", &f[1]), ("another compile", &f[2])] {
        let name = file.display().to_string();
        assert!(
            notes.iter().any(|n| n.contains(why) && n.contains(&name)),
            "no note says {name} is {why}: {notes:?}"
        );
    }
    let (fourth_image, fourth) = render();
    assert_eq!(fourth_image, image);
    assert!(
        fourth.iter().all(|(_, cached, note)| *cached && note.is_none()),
        "the damaged files were not replaced: {fourth:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
