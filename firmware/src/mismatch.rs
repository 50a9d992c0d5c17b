//! The frame a model monitor emits ([`crate::monitor`]), apart from the monitor so that the
//! node's estimator trait can name it without the monitor's machinery.

use edgekf::residual::{Mismatch, Statistic};

crate::frame! {
    /// A channel's innovations stopped fitting the model ([`edgekf::residual::Mismatch`]):
    /// emitted once per channel and statistic, after the poll in which it was found.
    #[derive(Eq)]
    pub struct MismatchFrame = "mismatch channel={=u8} statistic={=u8} since={=u32}" {
        /// The channel, from 0, in the order the image's docs give.
        pub channel: u8,
        /// 0: the CUSUM on the NIS (the variance grew); 1: the windowed mean (a bias); 2: the
        /// windowed autocorrelation (correlation left). See [`MismatchFrame::statistic`].
        pub statistic: u8,
        /// The sample, counted from 1 at start-up, where the change is estimated to begin.
        pub since: u32,
    }
}

impl MismatchFrame {
    /// The statistic the frame names (`None` for a code no monitor emits).
    ///
    /// ```
    /// use edgekf::residual::Statistic;
    /// use edgekf_firmware::frame::Frame;
    /// use edgekf_firmware::mismatch::MismatchFrame;
    /// let f = MismatchFrame::parse("mismatch channel=1 statistic=2 since=5000").unwrap().unwrap();
    /// assert_eq!((f.channel, f.statistic(), f.since), (1, Some(Statistic::Whiteness), 5000));
    /// ```
    pub fn statistic(&self) -> Option<Statistic> {
        Statistic::ALL.into_iter().find(|s| *s as u8 == self.statistic)
    }
}

impl From<Mismatch> for MismatchFrame {
    fn from(m: Mismatch) -> Self {
        Self { channel: m.channel, statistic: m.statistic as u8, since: m.since_sample }
    }
}
