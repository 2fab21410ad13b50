//! How far ahead of the pole the car flag's centre swings after braking.
use glam::Vec3;
use weft::scene::{Scene, load};

fn main() {
    let sets: Vec<load::Override> = std::env::args()
        .skip(1)
        .map(|s| s.parse().unwrap())
        .collect();
    let preset = load::load("flag_on_car", &sets).unwrap().preset;
    let mut scene = Scene::new(&preset).unwrap();
    let ahead = |scene: &Scene| {
        let car = scene.body_poses()[0];
        let x = &scene.solver().state().position;
        let centre = x.iter().copied().sum::<Vec3>() / x.len() as f32;
        (car.rotation * Vec3::X).dot(centre - car.transform_point(Vec3::new(-1.6, 0.55, 1.65)))
    };
    let (mut cruise, mut most, mut strain) = (0.0, f32::MIN, 0.0f32);
    while scene.time() < 8.0 {
        scene.step().unwrap();
        strain = strain.max(scene.solver().max_strain());
        if scene.time() < 5.9 {
            cruise = ahead(&scene);
        } else {
            most = most.max(ahead(&scene));
        }
    }
    println!("cruise {cruise:.3} most {most:.3} strain {strain:.4}");
}
