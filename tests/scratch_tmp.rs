#[test]
fn scratch() {
    let t = std::time::Instant::now();
    let l = glint::registry::BUILTINS
        .iter()
        .find(|l| l.name() == "disney_specular")
        .unwrap();
    let a = l.albedo(
        &[0.3, 0.2, 0.5, 0.5, 0.5],
        glint::math::Vec3::new(0.0, 0.6, 0.8),
        glint::lobes::Transport::Radiance,
    );
    eprintln!("first use {:?} {:?}", t.elapsed(), a);
}
