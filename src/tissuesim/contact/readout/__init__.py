"""What contact reports beyond the step: the force one body receives from another, an
instrument's force linearised for a haptic loop, a sphere probe's indentation depth."""
