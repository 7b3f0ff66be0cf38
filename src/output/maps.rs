//! The maps of a raster run in one table: the `/maps` dataset each is written to, the
//! name the avalanche-hazard literature gives it (pft, pfv, ppr as in AvaFrame, Tonnel
//! et al. 2023), its units, a long name for the GIS files and the description stored
//! with the dataset. The writer (`model::raster_maps`), the XDMF file, `granflow
//! export` and `granflow maps` all read it, so a map is named in one place.

/// One map of a raster run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapKind {
    /// Its `/maps` dataset.
    pub dataset: &'static str,
    /// Its name in exported files (`RUN_<short>.tif`).
    pub short: &'static str,
    pub units: &'static str,
    /// A short description for the GIS files' metadata (ASCII).
    pub long_name: &'static str,
    /// The `description` attribute of the dataset (ASCII: a GeoTIFF export copies it
    /// into an ASCII tag).
    pub description: &'static str,
}

/// The maps in the order of the file.
pub const MAPS: [MapKind; 5] = [
    MapKind {
        dataset: "h_max",
        short: "pft",
        units: "m",
        long_name: "peak flow thickness normal to the bed",
        description: "peak flow thickness (pft): the largest flow thickness normal to the bed over the run",
    },
    MapKind {
        dataset: "speed_max",
        short: "pfv",
        units: "m/s",
        long_name: "peak flow speed along the bed surface",
        description: "peak flow velocity (pfv): the largest flow speed along the bed surface over the run, where the thickness exceeds output.front_threshold",
    },
    MapKind {
        dataset: "ppr",
        short: "ppr",
        units: "Pa",
        long_name: "peak pressure rho |u|^2",
        // The writer names the run's density in it.
        description: "peak pressure (ppr): the largest rho |u|^2 over the run, in Pa (1 kPa = 1000 Pa)",
    },
    MapKind {
        dataset: "arrival_time",
        short: "arrival_time",
        units: "s",
        long_name: "arrival time of the flow",
        description: "arrival time: when the flow thickness first exceeded output.front_threshold (NaN where never reached)",
    },
    MapKind {
        dataset: "deposit",
        short: "deposit",
        units: "m",
        long_name: "deposit thickness",
        description: "deposit: the flow thickness normal to the bed at the end of the run (at the snapshot's time while it runs)",
    },
];

/// The `/maps` datasets, in the order of the file.
pub const MAP_DATASETS: [&str; 5] = [
    MAPS[0].dataset,
    MAPS[1].dataset,
    MAPS[2].dataset,
    MAPS[3].dataset,
    MAPS[4].dataset,
];
