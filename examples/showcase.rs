//! Writes `assets/models/showcase.glb`, the glTF showcase scene (see
//! `tests/common/showcase.rs`, which the tests share): `cargo run --example showcase`.

#[path = "../tests/common/showcase.rs"]
mod showcase;

fn main() -> std::io::Result<()> {
    let path = std::path::Path::new("assets/models/showcase.glb");
    let bytes = showcase::glb();
    std::fs::write(path, &bytes)?;
    println!("wrote {} ({} bytes)", path.display(), bytes.len());
    Ok(())
}
