//! libtorch through tch links, loads and computes on the CPU: a matmul and a conv2d with
//! numbers checked by hand.

use tch::{Device, Kind, Tensor};

#[test]
fn matmul_on_cpu() {
    let a = Tensor::from_slice(&[1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0]).view([2, 3]);
    let b = Tensor::from_slice(&[7.0f32, 8.0, 9.0, 10.0, 11.0, 12.0]).view([3, 2]);
    let c = a.matmul(&b);
    assert_eq!(c.size(), [2, 2]);
    assert_eq!(c.device(), Device::Cpu);
    let got: Vec<f32> = Vec::try_from(c.flatten(0, -1)).unwrap();
    assert_eq!(got, [58.0, 64.0, 139.0, 154.0]);
}

#[test]
fn conv2d_on_cpu() {
    // 1×1×3×3 input 0..9, one 2×2 kernel [[1, 0], [0, -1]], bias 0.5: each output is
    // x[i][j] - x[i+1][j+1] + 0.5 = -4 + 0.5.
    let input = Tensor::arange(9, (Kind::Float, Device::Cpu)).view([1, 1, 3, 3]);
    let weight = Tensor::from_slice(&[1.0f32, 0.0, 0.0, -1.0]).view([1, 1, 2, 2]);
    let bias = Tensor::from_slice(&[0.5f32]);
    let out = input.conv2d(&weight, Some(&bias), [1, 1], [0, 0], [1, 1], 1);
    assert_eq!(out.size(), [1, 1, 2, 2]);
    let got: Vec<f32> = Vec::try_from(out.flatten(0, -1)).unwrap();
    assert_eq!(got, [-3.5; 4]);

    // Padding 1 and a 3×3 box filter: the centre sums all nine (36), a corner four (0+1+3+4).
    let ones = Tensor::ones([1, 1, 3, 3], (Kind::Float, Device::Cpu));
    let boxed = input.conv2d(&ones, None::<Tensor>, [1, 1], [1, 1], [1, 1], 1);
    assert_eq!(boxed.double_value(&[0, 0, 1, 1]), 36.0);
    assert_eq!(boxed.double_value(&[0, 0, 0, 0]), 8.0);
}
