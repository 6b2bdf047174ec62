//! Mid-ranks of a pooled sample and its tie groups.

/// Mid-ranks (1-based, ties get the average of the ranks they span) of
/// `values`, and the size of every tie group with more than one member.
/// NaNs must be rejected by the caller.
pub fn midranks(values: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let n = values.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; n];
    let mut ties = Vec::new();
    let mut i = 0;
    while i < n {
        let mut j = i + 1;
        while j < n && values[order[j]] == values[order[i]] {
            j += 1;
        }
        // Positions i..j (0-based) hold ranks i+1..=j; their mean is (i+1+j)/2.
        let r = (i + 1 + j) as f64 / 2.0;
        for &k in &order[i..j] {
            ranks[k] = r;
        }
        if j - i > 1 {
            ties.push(j - i);
        }
        i = j;
    }
    (ranks, ties)
}

#[cfg(test)]
mod tests {
    use super::midranks;

    #[test]
    fn ties_share_the_average_rank() {
        let (r, t) = midranks(&[3.0, 1.0, 3.0, 2.0, 3.0, 0.5]);
        assert_eq!(r, vec![5.0, 2.0, 5.0, 3.0, 5.0, 1.0]);
        assert_eq!(t, vec![3]);
        let (r, t) = midranks(&[-0.0, 0.0]);
        assert_eq!(r, vec![1.5, 1.5]);
        assert_eq!(t, vec![2]);
    }
}
