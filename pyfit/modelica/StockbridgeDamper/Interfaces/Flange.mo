within StockbridgeDamper.Interfaces;
connector Flange "Translational flange: absolute position and cut force"
  Real s(unit="m") "Absolute position of the flange";
  flow Real f(unit="N") "Cut force, positive when it acts on the component in +s direction";
end Flange;
