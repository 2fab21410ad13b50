use glam::Vec3;
use weft::scene::{Scene, load};
fn main() {
    let sets: Vec<load::Override> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let preset = load::load("flag_on_car", &sets).unwrap().preset;
    let mut scene = Scene::new(&preset).unwrap();
    let spec = preset.cloth.spec();
    while scene.time() < 8.0 {
        scene.step().unwrap();
        if scene.frame() % 6 == 0 && scene.time() > 5.5 {
            let car = scene.body_poses()[0];
            let x = &scene.solver().state().position;
            let local = |i: u32| {
                let p: Vec3 =
                    (0..spec.warp).map(|j| x[spec.index(i, j)]).sum::<Vec3>() / spec.warp as f32;
                car.inverse_transform_point(p)
            };
            let n = scene.solver().state().normal(spec.index(0, 8));
            println!(
                "t={:.1} v={:.1} far={:.2?} mid={:.2?} pole_normal={:.2?}",
                scene.time(),
                0,
                local(spec.weft - 1).to_array(),
                local(spec.weft / 2).to_array(),
                (car.rotation.inverse() * n).to_array()
            );
        }
    }
}
