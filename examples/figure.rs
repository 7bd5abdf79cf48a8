//! Writes `assets/models/figure.glb`, the animated sample character (see
//! `tests/common/figure.rs`, which the tests share): `cargo run --example figure`.

#[path = "../tests/common/figure.rs"]
mod figure;
#[path = "../tests/common/showcase.rs"]
#[allow(dead_code)]
mod showcase;

fn main() -> std::io::Result<()> {
    let path = std::path::Path::new("assets/models/figure.glb");
    let bytes = figure::glb();
    std::fs::write(path, &bytes)?;
    println!("wrote {} ({} bytes)", path.display(), bytes.len());
    Ok(())
}
