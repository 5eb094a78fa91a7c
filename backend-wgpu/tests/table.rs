//! Tables (`backend_wgpu::table`): records copied, written and read back bit for bit across
//! rows, and a table larger than the adapter's textures refused with the limit named.

use backend_wgpu::GpuContext;
use backend_wgpu::table::{ROW_TEXELS, Table, Texel};
use ppm_core::passes::BackendError;
use std::process::ExitCode;
use test_support::{Need, Suite};
use wgpu::util::DeviceExt;

/// A storage buffer holding `words`, the source of a copy.
fn storage(ctx: &GpuContext, words: &[u32]) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("source"),
            contents: bytemuck::cast_slice(words),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        })
}

/// A buffer of whole rows and a part is copied whole, the partial row included, for both
/// texel kinds.
fn a_copy_fills_whole_rows_and_the_partial_last_row() {
    let ctx = &GpuContext::new().unwrap();
    for (texel, texels) in [
        (Texel::Words4, ROW_TEXELS + 17),
        (Texel::Word, 2 * ROW_TEXELS + 1),
    ] {
        let words = texels * texel.bytes() / 4;
        let data: Vec<u32> = (0..words).map(|i| i.wrapping_mul(2_654_435_761)).collect();
        let buffer = storage(ctx, &data);
        let table = Table::new(ctx, "table", texel, texels).expect("fits");
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        table.record_copy(&mut encoder, &buffer, texels);
        ctx.queue.submit([encoder.finish()]);
        let back = table.contents(ctx, texels);
        let first_wrong = back.iter().zip(&data).position(|(a, b)| a != b);
        assert_eq!(first_wrong, None, "{texel:?}: first wrong word");
        assert_eq!(back.len(), data.len());
    }
}

/// Records written at creation read back as written, floats bit for bit.
fn data_written_at_creation_reads_back_bit_for_bit() {
    let ctx = &GpuContext::new().unwrap();
    let floats = [
        f32::NAN,
        -0.0,
        f32::INFINITY,
        1e-45,
        -3.5,
        f32::MAX,
        0.1,
        7.0,
    ];
    let words: Vec<u32> = floats.iter().map(|f| f.to_bits()).collect();
    let table =
        Table::with_data(ctx, "floats", Texel::Words4, bytemuck::cast_slice(&words)).expect("fits");
    assert_eq!(table.contents(ctx, 2), words);
}

fn a_table_beyond_the_texture_limit_is_refused_naming_it() {
    let ctx = &GpuContext::new().unwrap();
    let rows = ctx.limits().max_texture_dimension_2d;
    match Table::new(
        ctx,
        "huge",
        Texel::Word,
        (rows + 1).saturating_mul(ROW_TEXELS),
    ) {
        Err(BackendError::Limit(m)) => {
            assert!(
                m.contains("huge") && m.contains("max_texture_dimension_2d"),
                "{m}"
            )
        }
        Err(e) => panic!("expected a limit error, got {e}"),
        Ok(_) => panic!("expected a limit error, got a table"),
    }
}

/// A write that starts near a row's end carries on at the next row's start, and leaves
/// every other texel as it was.
fn a_write_spans_rows_and_touches_nothing_else() {
    let ctx = &GpuContext::new().unwrap();
    let texels = 2 * ROW_TEXELS;
    let mut data: Vec<u32> = (0..texels * 4).collect();
    let table =
        Table::with_data(ctx, "table", Texel::Words4, bytemuck::cast_slice(&data)).expect("fits");
    let first = ROW_TEXELS - 3;
    let written: Vec<u32> = (0..10 * 4).map(|i| 1_000_000 + i).collect();
    table.write(ctx, first, bytemuck::cast_slice(&written));
    data[(first * 4) as usize..(first * 4) as usize + written.len()].copy_from_slice(&written);
    assert_eq!(table.contents(ctx, texels), data);
}

fn main() -> ExitCode {
    let adapter = Need::wgpu(|| GpuContext::new().map(drop).map_err(|e| e.to_string()));
    Suite::new()
        .test_needing(
            &[&adapter],
            "a_copy_fills_whole_rows_and_the_partial_last_row",
            a_copy_fills_whole_rows_and_the_partial_last_row,
        )
        .test_needing(
            &[&adapter],
            "data_written_at_creation_reads_back_bit_for_bit",
            data_written_at_creation_reads_back_bit_for_bit,
        )
        .test_needing(
            &[&adapter],
            "a_table_beyond_the_texture_limit_is_refused_naming_it",
            a_table_beyond_the_texture_limit_is_refused_naming_it,
        )
        .test_needing(
            &[&adapter],
            "a_write_spans_rows_and_touches_nothing_else",
            a_write_spans_rows_and_touches_nothing_else,
        )
        .run()
}
