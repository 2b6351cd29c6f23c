//! Plots of one episode (filled in below).
