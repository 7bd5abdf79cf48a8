use speculum::cpu_ref::lbvh as cref;
use speculum::cpu_ref::trace::CpuBvh;
#[test]
fn probe() {
    let mut cases: Vec<(String, Vec<speculum::gpu_types::GpuVertex>, Vec<u32>)> = Vec::new();
    for s in [
        speculum::scene::builtin::room().unwrap(),
        speculum::scene::builtin::mirrors().unwrap(),
    ] {
        cases.push((s.name.clone(), s.vertices.clone(), s.indices.clone()));
    }
    for name in ["spheres", "gallery", "/tmp/models/bunny.obj"] {
        let s = speculum::scene::load(name).unwrap();
        cases.push((name.into(), s.vertices.clone(), s.indices.clone()));
    }
    let (v, i) =
        speculum::scene::soup::random_soup(100000, 10.0, speculum::scene::soup::default_size(100000) * 10.0, 1);
    cases.push(("soup".into(), v, i));
    for (name, v, i) in cases {
        let n = i.len() / 3;
        let keys = cref::morton_keys(&v, &i, 1);
        let (sk, sv) = cref::sort_pairs(&keys, &(0..n as u32).collect::<Vec<_>>());
        let binned = CpuBvh::build(&v, &i).sah_cost();
        let t = std::time::Instant::now();
        let l = cref::build(&sk, &sv, &v, &i);
        let tl = t.elapsed().as_secs_f64();
        cref::check_bvh(&l, &v, &i).unwrap();
        print!(
            "{name} n={n}: lbvh {:.3} ({tl:.2}s)",
            cref::sah_cost(&l.nodes, n) / binned
        );
        for r in [4, 8, 16] {
            let t = std::time::Instant::now();
            let p = cref::ploc(&sv, &v, &i, r);
            let tp = t.elapsed().as_secs_f64();
            cref::check_bvh(&p, &v, &i).unwrap();
            print!("  ploc{r} {:.3} ({tp:.2}s)", cref::sah_cost(&p.nodes, n) / binned);
        }
        println!();
    }
}
